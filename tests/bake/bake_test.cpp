// magbake bake, diff and info through the real binary: determinism, resume, crash safety,
// golden caches and bad input.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "cli.h"
#include "io/cache.h"
#include "io/diff.h"
#include "scene/load.h"
#include "scene/scene_magnetics.h"
#include "support/shell.h"

namespace magbake::testing {
namespace {
namespace fs = std::filesystem;

std::string exe() { return MAGBAKE_EXE; }
std::string src(const std::string& rel) { return std::string(MAGBAKE_SOURCE_DIR) + "/" + rel; }

class Bake : public ::testing::Test {
 protected:
  fs::path dir;
  void SetUp() override {
    dir = fresh_temp_dir("magbake_bake_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir);  // kept for a look when the test failed
  }
  Outcome bake(const std::string& scene, const std::string& out, const std::string& extra = "") {
    return sh(exe() + " " + extra + " bake " + scene + " -o " + (dir / out).string());
  }
  // For each k: a .partial holding the first k frames of `reader` (copied bit for bit, as an
  // interrupted bake leaves them) is resumed on 1 thread and must give `full` to the last bit.
  void expect_resumes_match(const std::string& scene_file, const scene::Scene& scene, const io::CacheReader& reader,
                            const std::string& full, const std::string& cache_name, std::initializer_list<int> cuts) {
    const magnetics::Model model = scene::build_magnetics_model(scene);
    for (int k : cuts) {
      const fs::path out = dir / ("cut" + std::to_string(k));
      fs::create_directories(out);
      {
        io::CacheWriter w((out / (cache_name + ".partial")).string(), scene, model, "test");
        w.copy_frames_from(reader, k);
        w.set_status(io::BakeStatus::kInterrupted);
      }
      ASSERT_EQ(sh(exe() + " --threads 1 bake " + scene_file + " -o " + out.string() + " --resume").code, 0) << k;
      const Outcome d = sh(exe() + " diff --exact " + full + " " + (out / cache_name).string());
      EXPECT_EQ(d.code, 0) << "resumed after " << k << " frames:\n" << d.out;
    }
  }
};

TEST_F(Bake, SameThreadCountOrNotTheCacheIsIdentical) {
  const std::string scene = src("tests/golden/sphere_pickup.yaml");
  ASSERT_EQ(bake(scene, "t1", "--threads 1").code, 0);
  ASSERT_EQ(bake(scene, "t2", "--threads 2").code, 0);
  ASSERT_EQ(bake(scene, "t2b", "--threads 2").code, 0);
  const std::string a = (dir / "t1/sphere_pickup.h5").string(), b = (dir / "t2/sphere_pickup.h5").string(),
                    c = (dir / "t2b/sphere_pickup.h5").string();
  const Outcome d12 = sh(exe() + " diff --exact " + a + " " + b);
  EXPECT_EQ(d12.code, 0) << d12.out;
  EXPECT_NE(d12.out.find("bit for bit"), std::string::npos);
  EXPECT_EQ(sh(exe() + " diff --exact " + b + " " + c).code, 0);
}

// diff lines frames up by frame number (issue 16): a bake of frames 10-20 (simulated from the
// first frame, written from the tenth) is frames 10-20 of the full bake bit for bit, and the
// frames that only the full bake holds are named.
TEST_F(Bake, DiffLinesFramesUpByNumberAndNamesTheOnesInOneCacheOnly) {
  const std::string scene = src("tests/golden/sphere_pickup.yaml");
  ASSERT_EQ(bake(scene, "full", "--threads 1 --quiet").code, 0);
  ASSERT_EQ(sh(exe() + " --threads 1 --quiet bake " + scene + " --frames 10-20 -o " + (dir / "part").string()).code, 0);
  const std::string full = (dir / "full/sphere_pickup.h5").string(), part = (dir / "part/sphere_pickup.h5").string();
  const Outcome d = sh(exe() + " diff --exact " + full + " " + part);
  EXPECT_EQ(d.code, 1) << d.out;  // frames in one cache only: they differ
  EXPECT_NE(d.out.find("frames only in " + full + ": 1-9, 21-25"), std::string::npos) << d.out;
  EXPECT_EQ(d.out.find("position"), std::string::npos) << "the common frames 10-20 should be identical:\n" << d.out;
  const Outcome swapped = sh(exe() + " diff " + part + " " + full);
  EXPECT_EQ(swapped.code, 1);
  EXPECT_NE(swapped.out.find("frames only in " + full + ": 1-9, 21-25"), std::string::npos) << swapped.out;
}

// A complete cache is a finished bake: baking into its folder again exits 2 and leaves it as it
// was; --force replaces it, --resume finds it complete and does nothing.
TEST_F(Bake, ACompleteCacheIsReplacedOnlyWithForce) {
  const std::string scene = src("tests/golden/sphere_pickup.yaml");
  ASSERT_EQ(bake(scene, "f", "--quiet").code, 0);
  const fs::path cache = dir / "f/sphere_pickup.h5";
  const auto written = fs::last_write_time(cache);
  const auto size = fs::file_size(cache);
  const Outcome again = bake(scene, "f", "--quiet");
  EXPECT_EQ(again.code, 2) << again.out;
  EXPECT_NE(again.out.find("is already a complete bake: --force replaces it"), std::string::npos) << again.out;
  EXPECT_EQ(fs::last_write_time(cache), written);
  EXPECT_EQ(fs::file_size(cache), size);
  EXPECT_FALSE(fs::exists(dir / "f/sphere_pickup.h5.partial"));
  const Outcome resumed = sh(exe() + " bake " + scene + " -o " + (dir / "f").string() + " --resume");
  EXPECT_EQ(resumed.code, 0) << resumed.out;
  EXPECT_NE(resumed.out.find("nothing to resume"), std::string::npos) << resumed.out;
  const Outcome forced = sh(exe() + " --quiet bake " + scene + " -o " + (dir / "f").string() + " --force");
  EXPECT_EQ(forced.code, 0) << forced.out;
  EXPECT_NE(fs::last_write_time(cache), written);
  EXPECT_EQ(sh(exe() + " diff --exact " + cache.string() + " " + cache.string()).code, 0);
}

// --every on field and preview counts from the shot's first frame, whatever the range, so split
// runs write the frames a whole run writes; a pattern that names no frame is refused (exit 2).
TEST_F(Bake, EveryCountsFromTheShotsFirstFrameAndPatternsMustNameTheFrame) {
  const std::string scene = src("tests/golden/sphere_pickup.yaml");
  ASSERT_EQ(bake(scene, "e", "--quiet").code, 0);
  const std::string cache = (dir / "e/sphere_pickup.h5").string();
  const Outcome f = sh(exe() + " --quiet field " + cache + " --frames 5-20 --every 6 -o " + (dir / "v/f.####.vdb").string());
  ASSERT_EQ(f.code, 0) << f.out;
  std::vector<std::string> vdbs, pngs;
  for (const auto& e : fs::directory_iterator(dir / "v")) vdbs.push_back(e.path().filename().string());
  std::sort(vdbs.begin(), vdbs.end());
  EXPECT_EQ(vdbs, (std::vector<std::string>{"f.0007.vdb", "f.0013.vdb", "f.0019.vdb"}));  // 1, 7, 13, 19, 25 in 5-20
  const Outcome p = sh(exe() + " --quiet preview " + cache + " --every 10 --size 64x48 -o " + (dir / "p/p.####.png").string());
  ASSERT_EQ(p.code, 0) << p.out;
  for (const auto& e : fs::directory_iterator(dir / "p")) pngs.push_back(e.path().filename().string());
  std::sort(pngs.begin(), pngs.end());
  EXPECT_EQ(pngs, (std::vector<std::string>{"p.0001.png", "p.0011.png", "p.0021.png"}));
  for (const std::string& cmd : {"field " + cache + " -o " + (dir / "w/f.vdb").string(),
                                 "preview " + cache + " -o " + (dir / "w/p.png").string()}) {
    const Outcome bad = sh(exe() + " " + cmd);
    EXPECT_EQ(bad.code, 2) << cmd << "\n" << bad.out;
    EXPECT_NE(bad.out.find("names no frame"), std::string::npos) << bad.out;
  }
  EXPECT_FALSE(fs::exists(dir / "w/f.vdb"));
}

TEST_F(Bake, GoldenCachesStillMatch) {
  for (const char* name : {"magnets_in_space", "sphere_pickup"}) {
    ASSERT_EQ(bake(src(std::string("tests/golden/") + name + ".yaml"), "g").code, 0);
    const Outcome d = sh(exe() + " diff " + src(std::string("tests/golden/") + name + ".h5") + " " +
                         (dir / "g" / (std::string(name) + ".h5")).string());
    EXPECT_EQ(d.code, 0) << name << "\n" << d.out;
  }
}

// The same binary must bake the same cache on any x86-64-v3 CPU. qemu-user runs it on an
// emulated Intel (Haswell) and AMD (EPYC-Rome) CPU: other cpuid (vendor, cache sizes, features,
// so other library dispatch and Eigen blocking) and instructions computed in software. An
// instruction whose result is implementation-defined (the rsqrtps/rcpps estimates, which Intel
// and AMD compute differently) gives other bits under emulation than on the host, and so does
// any code path chosen by CPU model. The scenes cover cuboid and cylinder magnets in contact,
// induction with the preconditioner, soft spheres and a mesh magnet (tst).
TEST_F(Bake, SameCacheOnEmulatedIntelAndAmdCpus) {
  ASSERT_EQ(sh("command -v qemu-x86_64").code, 0) << "qemu-user is missing (scripts/install-deps.sh installs it)";
  struct Case {
    std::string scene, cache, frames;
  };
  // TST without its previews: the cache is what is compared, and field lines under emulation
  // cost minutes.
  std::ifstream tst_in(src("scenes/paper/tst.yaml"));
  std::string tst((std::istreambuf_iterator<char>(tst_in)), std::istreambuf_iterator<char>());
  ASSERT_NE(tst.find("\noutputs:"), std::string::npos);
  tst = tst.substr(0, tst.find("\noutputs:")) + "\noutputs:\n  cache: tst.h5\n";
  std::ofstream(dir / "tst.yaml") << tst;
  const Case cases[] = {{src("tests/golden/magnets_in_space.yaml"), "magnets_in_space.h5", ""},
                        {src("tests/golden/sphere_pickup.yaml"), "sphere_pickup.h5", ""},
                        {(dir / "tst.yaml").string(), "tst.h5", " --frames 1-2"}};
  for (const Case& c : cases) {
    ASSERT_EQ(sh(exe() + " -q bake " + c.scene + c.frames + " -o " + (dir / "host").string()).code, 0) << c.scene;
    for (const char* cpu : {"Haswell", "EPYC-Rome"}) {
      const fs::path out = dir / cpu;
      const Outcome q = sh("qemu-x86_64 -cpu " + std::string(cpu) + " " + exe() + " -q bake " + c.scene + c.frames +
                           " -o " + out.string());
      ASSERT_EQ(q.code, 0) << cpu << " " << c.scene << "\n" << q.out;
      const Outcome d = sh(exe() + " diff --exact " + (dir / "host" / c.cache).string() + " " + (out / c.cache).string());
      EXPECT_EQ(d.code, 0) << "on an emulated " << cpu << " CPU " << c.scene << " bakes another cache:\n" << d.out;
    }
  }
}

// The kernels must not use instructions whose results differ between CPU models: the
// reciprocal and reciprocal-square-root estimates (SSE/AVX rcp*, rsqrt*; AVX-512 rcp14/28,
// rsqrt14/28). Complements the emulation test, which only sees the code paths its scenes run.
TEST_F(Bake, NoCpuDependentEstimateInstructionsInTheBinary) {
  const Outcome o = sh("objdump -d --no-show-raw-insn " + exe() +
                       " | grep -E '\\s(v?rcp(ps|ss|14ps|14pd|14ss|14sd|28ps|28pd)|v?rsqrt(ps|ss|14ps|14pd|14ss|14sd|28ps|28pd))\\s' | head -5");
  ASSERT_EQ(o.code, 0) << o.out;
  EXPECT_EQ(o.out, "") << "estimate instructions in magbake:\n" << o.out;
}

TEST_F(Bake, DiffReportsTheFirstFrameAndLargestDeviationPerBody) {
  // Same scene, one body nudged: diff must say which body, from which frame, by how much.
  std::ifstream in(src("tests/golden/magnets_in_space.yaml"));
  std::string text((std::istreambuf_iterator<char>(in)), {});
  text.replace(text.find("position: [14, 3, 2]"), 20, "position: [14, 3, 2.01]");
  std::ofstream(dir / "nudged.yaml") << text;
  ASSERT_EQ(bake((dir / "nudged.yaml").string(), "n").code, 0);
  const Outcome d = sh(exe() + " diff " + src("tests/golden/magnets_in_space.h5") + " " +
                       (dir / "n/magnets_in_space.h5").string());
  EXPECT_EQ(d.code, 1) << d.out;
  EXPECT_NE(d.out.find("b                    position"), std::string::npos) << d.out;
  EXPECT_NE(d.out.find("baked from different scene files"), std::string::npos);
  // ...tolerances above every difference accept it, and the orientation tolerance is applied on
  // its own: the nudged magnets stick and tumble in other orientations (0.091 rad apart at
  // frame 30), so 0.12 rad accepts and 0.06 rad refuses, with the other tolerances unchanged.
  const std::string pair = src("tests/golden/magnets_in_space.h5") + " " + (dir / "n/magnets_in_space.h5").string();
  EXPECT_EQ(sh(exe() + " diff --atol 1e4 --rtol 1 --angle-tol 0.12 " + pair).code, 0);
  const Outcome tight = sh(exe() + " diff --atol 1e4 --rtol 1 --angle-tol 0.06 " + pair);
  EXPECT_EQ(tight.code, 1) << tight.out;
  EXPECT_NE(tight.out.find("orientation"), std::string::npos) << tight.out;
  EXPECT_EQ(tight.out.find("position "), std::string::npos) << tight.out;
}

// Runs a bake in the background and sends `sig` once its progress passes `percent`.
int bake_and_signal(const std::string& scene, const fs::path& out, int sig, int percent) {
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string o = out.string();
    const int fd = ::open((o + ".log").c_str(), O_CREAT | O_WRONLY | O_TRUNC, 0644);
    dup2(fd, 1), dup2(fd, 2);
    execl(MAGBAKE_EXE, MAGBAKE_EXE, "--threads", "1", "bake", scene.c_str(), "-o", o.c_str(), (char*)nullptr);
    _exit(127);
  }
  // Not a tty: the bake prints "Progress: bake NN% frame F/L" lines to the log.
  // Waits up to 10 minutes (a sanitizer build bakes the demo at ~1 s per frame).
  bool reached = false;
  for (int i = 0; i < 120000 && !reached; ++i) {
    std::ifstream log(out.string() + ".log");
    std::string line, last;
    while (std::getline(log, line)) {
      if (line.rfind("Progress: bake ", 0) == 0) last = line;
    }
    reached = !last.empty() && std::stoi(last.substr(15)) >= percent;
    if (!reached) usleep(5000);
  }
  EXPECT_TRUE(reached) << "the bake never reported " << percent << "%";
  kill(pid, sig);
  int st = 0;
  waitpid(pid, &st, 0);
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

TEST_F(Bake, InterruptedBakeResumesAndMatches) {
  const std::string scene = src("tests/golden/sphere_pickup.yaml");
  ASSERT_EQ(bake(scene, "full", "--threads 1").code, 0);
  const int code = bake_and_signal(scene, dir / "cut", SIGTERM, 40);
  ASSERT_EQ(code, 75) << "exit code of an interrupted bake";
  const fs::path partial = dir / "cut/sphere_pickup.h5.partial";
  ASSERT_TRUE(fs::exists(partial));
  EXPECT_FALSE(fs::exists(dir / "cut/sphere_pickup.h5"));  // never under the final name
  int kept = 0;
  {
    const io::CacheReader r(partial.string());
    EXPECT_EQ(r.status(), io::BakeStatus::kInterrupted);
    kept = r.frame_count();
    ASSERT_GT(kept, 0);
    ASSERT_LT(kept, 25);
  }
  const Outcome r = sh(exe() + " --threads 1 bake " + scene + " -o " + (dir / "cut").string() + " --resume");
  ASSERT_EQ(r.code, 0) << r.out;
  // The report counts the whole cache, and what was kept.
  EXPECT_NE(r.out.find("(25 frames: " + std::to_string(kept) + " kept from the interrupted bake, " +
                       std::to_string(25 - kept) + " baked now)"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(partial));
  const io::CacheReader full((dir / "full/sphere_pickup.h5").string()), resumed((dir / "cut/sphere_pickup.h5").string());
  ASSERT_EQ(resumed.frame_count(), 25);
  // Frames before the interruption: bit for bit.
  for (int f = 0; f < kept; ++f) {
    const io::CacheFrame a = full.frame(f), b = resumed.frame(f);
    for (std::size_t i = 0; i < a.position.size(); ++i) {
      EXPECT_EQ(a.position[i], b.position[i]) << "frame " << f;
      EXPECT_EQ(a.orientation[i].coeffs(), b.orientation[i].coeffs()) << "frame " << f;
      EXPECT_EQ(a.velocity[i], b.velocity[i]) << "frame " << f;
    }
  }
  // Later frames: bit for bit too (every frame of a bake starts from what the cache holds).
  const Outcome d = sh(exe() + " diff --exact " + (dir / "full/sphere_pickup.h5").string() + " " +
                       (dir / "cut/sphere_pickup.h5").string());
  EXPECT_EQ(d.code, 0) << "resumed after " << kept << " frames:\n" << d.out;
}

// Resume is exact wherever the bake stops: a .partial holding the first k frames of an
// uninterrupted bake (copied bit for bit, as an interrupted bake leaves them), resumed, gives
// the uninterrupted cache to the last bit (diff --exact: poses, velocities, forces, induced
// moments, energies, work counters), for k across a shot of tumbling and resting contact,
// stuck contacts and sleep. The full bake runs on 2 threads, the resumed ones on 1.
TEST_F(Bake, AResumeAfterAnyFrameGivesTheUninterruptedCacheBitForBit) {
  const std::string scene_file = src("tests/data/resume_tumble.yaml");
  ASSERT_EQ(bake(scene_file, "full", "--threads 2").code, 0);
  const std::string full = (dir / "full/tumble.h5").string();
  const scene::Scene scene = scene::load_scene(scene_file);
  const io::CacheReader reader(full);
  ASSERT_EQ(reader.frame_count(), 45);
  // The shot must exercise what resume has to carry: stuck contacts and sleep.
  const std::vector<double> asleep = reader.observable("sleeping");
  EXPECT_GT(*std::max_element(asleep.begin(), asleep.end()), 0) << "nothing fell asleep";
  int stuck_frames = 0;
  for (int f = 0; f < reader.frame_count(); ++f) stuck_frames += !reader.stuck_rows(f).empty();
  EXPECT_GT(stuck_frames, 0) << "no stuck contact in the shot";
  std::printf("tumble: %d of 45 frames with stuck contacts, at most %g bodies asleep\n", stuck_frames,
              *std::max_element(asleep.begin(), asleep.end()));
  expect_resumes_match(scene_file, scene, reader, full, "tumble.h5", {1, 2, 4, 7, 10, 13, 17, 21, 26, 33, 44});
}

// Joints (scene 1.1) are remade from the scene at every frame, like the world they live in:
// resumed after any frame, a shot of hinges, a ball joint and a slider gives the uninterrupted
// cache bit for bit (full bake on 2 threads, resumed ones on 1).
TEST_F(Bake, AResumedShotWithJointsGivesTheUninterruptedCacheBitForBit) {
  const std::string scene_file = src("tests/data/resume_joints.yaml");
  ASSERT_EQ(bake(scene_file, "full", "--threads 2").code, 0);
  const std::string full = (dir / "full/joints.h5").string();
  const scene::Scene scene = scene::load_scene(scene_file);
  ASSERT_EQ(scene.joints.size(), 5u);
  const io::CacheReader reader(full);
  ASSERT_EQ(reader.frame_count(), 40);
  expect_resumes_match(scene_file, scene, reader, full, "joints.h5", {1, 9, 23, 38});
}

// Saturation (scene 1.1): each evaluation's Newton steps start from the moments in the state
// (the cache's induced moments), so a resumed bake of saturating balls falling onto magnets and
// touching them gives the uninterrupted cache bit for bit.
TEST_F(Bake, AResumedShotWithSaturatingSteelGivesTheUninterruptedCacheBitForBit) {
  const std::string scene_file = src("tests/data/resume_saturation.yaml");
  ASSERT_EQ(bake(scene_file, "full", "--threads 2").code, 0);
  const std::string full = (dir / "full/saturation.h5").string();
  const scene::Scene scene = scene::load_scene(scene_file);
  ASSERT_EQ(scene.materials[2].saturation, 0.4);
  const io::CacheReader reader(full);
  ASSERT_EQ(reader.frame_count(), 30);
  expect_resumes_match(scene_file, scene, reader, full, "saturation.h5", {1, 9, 23});
}

// Sleeping is in the cache: a bake interrupted while its magnets sleep resumes asleep (the
// cache's /particles/bodies/sleep and sleep_reference), so later frames are the uninterrupted
// bake's (positions bit for bit). (Resumed awake, the chain would chatter at ~30 um/s and take 240 substeps a
// frame instead of 20.)
TEST_F(Bake, ABakeInterruptedWhileAsleepResumesAsleep) {
  const fs::path scene = dir / "chain.yaml";
  {
    std::ofstream f(scene);
    f << "magbake: 1\nname: chain\nunits: {length: mm, angle: deg}\n"
         "time: {fps: 50, frames: [1, 60], dt: 0.001, sleep: 0.5}\ngravity: [0, 0, -9810]\n"
         "materials:\n  N42: {kind: permanent, remanence: 1.3, density: 7500}\n  wood: {kind: none, density: 700}\n"
         "bodies:\n  - {name: table, shape: {box: [300, 300, 10]}, material: wood, motion: static, position: [0, 0, -5]}\n";
    for (int k = 0; k < 4; ++k) {
      f << "  - {name: ball_" << k << ", shape: {sphere: {radius: 2.5}}, material: N42, magnetization: [1, 0, 0], position: ["
        << -7.5 + 5.0 * k << ", 0, 2.5], friction: 0.5}\n";
    }
  }
  ASSERT_EQ(bake(scene.string(), "full", "--threads 1").code, 0);
  ASSERT_EQ(bake_and_signal(scene.string(), dir / "cut", SIGTERM, 70), 75);
  int kept = 0;
  {
    const io::CacheReader r((dir / "cut/chain.h5.partial").string());
    kept = r.frame_count();
  }
  ASSERT_EQ(sh(exe() + " --threads 1 bake " + scene.string() + " -o " + (dir / "cut").string() + " --resume").code, 0);
  const io::CacheReader full((dir / "full/chain.h5").string()), resumed((dir / "cut/chain.h5").string());
  ASSERT_EQ(resumed.frame_count(), 60);
  const std::vector<double> asleep = full.observable("sleeping"), asleep_resumed = resumed.observable("sleeping");
  ASSERT_EQ(asleep.size(), 60u);
  ASSERT_EQ(asleep[kept - 1], 4) << "the cut (after " << kept << " frames) should fall while all four sleep";
  EXPECT_EQ(asleep_resumed, asleep);
  for (int f = kept; f < 60; ++f) {
    const io::CacheFrame a = full.frame(f), b = resumed.frame(f);
    for (std::size_t i = 0; i < a.position.size(); ++i) {
      EXPECT_EQ(a.position[i], b.position[i]) << "frame " << f << " body " << i;
      EXPECT_EQ(a.orientation[i].coeffs(), b.orientation[i].coeffs()) << "frame " << f << " body " << i;
    }
    EXPECT_EQ(a.sleep, b.sleep) << "frame " << f;
    EXPECT_EQ(a.sleep_reference, b.sleep_reference) << "frame " << f;
  }
}

TEST_F(Bake, KillNineLeavesAReadableCacheWithEveryCompletedFrame) {
  const std::string scene = src("scenes/demo.yaml");
  const int code = bake_and_signal(scene, dir / "k", SIGKILL, 30);
  EXPECT_EQ(code, 128 + SIGKILL);
  const fs::path partial = dir / "k/demo.h5.partial";
  ASSERT_TRUE(fs::exists(partial));
  const io::CacheReader r(partial.string());
  EXPECT_EQ(r.status(), io::BakeStatus::kRunning);  // killed: never marked
  ASSERT_GE(r.frame_count(), 20);                     // 30% of 90 frames were reported done
  // Every completed frame reads back, and matches an uninterrupted bake's frames.
  ASSERT_EQ(sh(exe() + " --threads 1 bake " + scene + " -o " + (dir / "ref").string() + " --cache-only").code, 0);
  const io::CacheReader ref((dir / "ref/demo.h5").string());
  for (int f = 0; f < r.frame_count(); ++f) {
    const io::CacheFrame a = r.frame(f), b = ref.frame(f);
    EXPECT_EQ(a.frame, b.frame);
    for (std::size_t i = 0; i < a.position.size(); ++i) EXPECT_EQ(a.position[i], b.position[i]) << f;
  }
  // info works on it, and so does --resume.
  EXPECT_EQ(sh(exe() + " info " + partial.string()).code, 0);
  EXPECT_EQ(sh(exe() + " --threads 1 bake " + scene + " -o " + (dir / "k").string() + " --resume --cache-only").code, 0);
  EXPECT_TRUE(fs::exists(dir / "k/demo.h5"));
}

TEST_F(Bake, NumericalFaultStopsWithBodyAndFrameAndKeepsGoodFrames) {
  // In process, through the bake command's test seam: the ball's force turns NaN while frame 7
  // is computed.
  cli::BakeHooks hooks;
  hooks.after_magnetics = [](int frame, sim::SimState& s) {
    if (frame == 7) s.magnetic_force[1][0] = std::numeric_limits<double>::quiet_NaN();  // body 1 = ball
  };
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const int code = cli::cmd_bake(src("tests/golden/sphere_pickup.yaml"), (dir / "nan").string(), "", false,
                                 cli::Global{0, true, false}, false, false, hooks);
  const std::string out = ::testing::internal::GetCapturedStdout() + ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, 1);
  EXPECT_NE(out.find("non-finite magnetic force or torque on body 'ball' while computing frame 7"), std::string::npos)
      << out;
  const io::CacheReader c((dir / "nan/sphere_pickup.h5.partial").string());
  EXPECT_EQ(c.status(), io::BakeStatus::kFailed);
  EXPECT_EQ(c.frame_count(), 6);
  EXPECT_FALSE(fs::exists(dir / "nan/sphere_pickup.h5"));
}

TEST_F(Bake, UnwritableOutputFolderIsAClearError) {
  std::ofstream(dir / "a_file") << "x";
  const Outcome r = bake(src("tests/golden/sphere_pickup.yaml"), "a_file/sub");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("cannot create the output folder"), std::string::npos) << r.out;
  if (geteuid() != 0) {  // root writes anywhere: permissions only bind other users
    fs::create_directories(dir / "ro");
    fs::permissions(dir / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    const Outcome p = bake(src("tests/golden/sphere_pickup.yaml"), "ro");
    EXPECT_EQ(p.code, 2);
    EXPECT_NE(p.out.find("not writable"), std::string::npos) << p.out;
  }
}

TEST_F(Bake, FullDiskFailsCleanlyWithoutAFinalFile) {
  // A real full disk: a 96 KiB tmpfs when we may mount one (root in CI); else a file-size limit
  // (ulimit -f, SIGXFSZ ignored), which fails writes the same way (EFBIG instead of ENOSPC).
  const fs::path mnt = dir / "tiny";
  fs::create_directories(mnt);
  const bool mounted = geteuid() == 0 && ::mount("tmpfs", mnt.c_str(), "tmpfs", 0, "size=96k") == 0;
  const std::string scene = src("scenes/demo.yaml");
  Outcome r;
  if (mounted) {
    r = bake(scene, "tiny");
  } else {
    r = sh("trap '' XFSZ; ulimit -f 96; " + exe() + " bake " + scene + " -o " + mnt.string());
  }
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_TRUE(r.out.find("writing the cache failed") != std::string::npos ||
              r.out.find("cannot start the cache") != std::string::npos)
      << r.out;
  EXPECT_TRUE(r.out.find("No space left on device") != std::string::npos ||
              r.out.find("File too large") != std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(mnt / "demo.h5"));
  if (mounted) ::umount(mnt.c_str());
  std::printf("full disk: %s\n", mounted ? "real tmpfs" : "file-size limit");
}

TEST_F(Bake, ForeignCorruptAndMissingFilesAreErrorsForDiffAndInfo) {
  std::ofstream(dir / "random.h5") << "this is not HDF5 at all";
  // A valid HDF5 file that is not a cache.
  {
    const hid_t f = H5Fcreate((dir / "foreign.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    H5Fclose(f);
  }
  // A truncated cache.
  fs::copy_file(src("tests/golden/sphere_pickup.h5"), dir / "truncated.h5");
  fs::resize_file(dir / "truncated.h5", 3000);
  const std::string good = src("tests/golden/sphere_pickup.h5");
  for (const char* bad : {"random.h5", "foreign.h5", "truncated.h5", "missing.h5"}) {
    const Outcome d = sh(exe() + " diff " + good + " " + (dir / bad).string());
    EXPECT_EQ(d.code, 2) << bad << "\n" << d.out;
    const Outcome i = sh(exe() + " info " + (dir / bad).string());
    EXPECT_EQ(i.code, 2) << bad << "\n" << i.out;
  }
  EXPECT_NE(sh(exe() + " info " + (dir / "foreign.h5").string()).out.find("not a magbake cache"), std::string::npos);
  EXPECT_NE(sh(exe() + " info " + (dir / "random.h5").string()).out.find("not an HDF5 file"), std::string::npos);
}

// A bake that also writes field volumes and previews is one job for the farm: each stage's
// lines name it and the frame, and the job's `Progress: NN%` and ALF_PROGRESS rise through the
// stages (bake 80%, field and preview 10% each) without ever going back, to 100% once.
TEST_F(Bake, FarmProgressNamesTheStageAndRisesOverTheWholeJob) {
  std::ifstream in(src("tests/golden/magnets_in_space.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  const fs::path scene = dir / "job.yaml";
  std::ofstream(scene) << text.str() << "outputs:\n  cache: job.h5\n  field: {path: f.####.vdb, voxel: 2, every: 2}\n"
                       << "  preview: {path: p.####.png, size: [64, 36]}\n";
  const Outcome r = sh(exe() + " bake " + scene.string() + " -o " + (dir / "job").string() + " --frames 3-12");
  ASSERT_EQ(r.code, 0) << r.out;
  std::istringstream lines(r.out);
  std::string line, stages;
  int last_alf = -1, alf_lines = 0, plain = -1;
  while (std::getline(lines, line)) {
    if (line.rfind("ALF_PROGRESS ", 0) == 0) {
      const int alf = std::stoi(line.substr(13));
      EXPECT_GT(alf, last_alf) << line;
      EXPECT_EQ(plain, alf) << "the plain Progress line before it";
      last_alf = alf, ++alf_lines;
    } else if (line.rfind("Progress: ", 0) == 0 && std::isdigit(static_cast<unsigned char>(line[10]))) {
      plain = std::stoi(line.substr(10));
    } else if (line.rfind("Progress: ", 0) == 0) {
      const std::string stage = line.substr(10, line.find(' ', 10) - 10);
      if (stages.empty() || stages.substr(stages.rfind(' ') + 1) != stage) stages += " " + stage;
    }
  }
  EXPECT_EQ(stages, " bake field preview");
  EXPECT_EQ(last_alf, 100);
  EXPECT_GE(alf_lines, 20);
  EXPECT_NE(r.out.find("Progress: bake 100% frame 12/12\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ALF_PROGRESS 80%\n"), std::string::npos) << r.out;
  // Field volumes every 2nd frame from 3: 3, 5, ..., 11 (the last is 11 of 11).
  EXPECT_NE(r.out.find("Progress: field 100% frame 11/11\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Progress: preview 100% frame 12/12\n"), std::string::npos) << r.out;
}

TEST_F(Bake, FarmProgressLinesAndFrameRange) {
  const Outcome r = sh(exe() + " bake " + src("tests/golden/magnets_in_space.yaml") + " -o " + (dir / "p").string() +
                       " --frames 1-10");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("Progress: bake 10% frame 1/10\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Progress: bake 100% frame 10/10\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Progress: 100%\nALF_PROGRESS 100%\n"), std::string::npos) << r.out;
  EXPECT_EQ(io::CacheReader((dir / "p/magnets_in_space.h5").string()).frame_count(), 10);
  EXPECT_EQ(sh(exe() + " bake " + src("tests/golden/magnets_in_space.yaml") + " --frames 5-2").code, 2);
  EXPECT_EQ(sh(exe() + " bake " + src("tests/golden/magnets_in_space.yaml") + " --frames 1-999").code, 2);
}

TEST_F(Bake, CacheIsReadableByH5py) {
  const Outcome r = sh("/usr/bin/python3 " + src("tests/bake/read_cache.py") + " " + src("tests/golden/sphere_pickup.h5"));
  EXPECT_EQ(r.code, 0) << r.out;
}

}  // namespace
}  // namespace magbake::testing
