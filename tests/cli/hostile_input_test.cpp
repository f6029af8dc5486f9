// Bad input never crashes, and nothing incomplete looks complete (issue 12): scenes, caches,
// patterns and command-line numbers as a hostile or careless user gives them, through the real
// binary. Every case exits with a clear message and code 2 (bad input) or 1 (failure), never a
// signal, and leaves no final-named output that is incomplete.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "support/shell.h"

// GCC 12 reports a false -Wrestrict in inlined std::string concatenation (GCC bug 105329).
#pragma GCC diagnostic ignored "-Wrestrict"

namespace magbake::testing {
namespace {
namespace fs = std::filesystem;

std::string exe() { return MAGBAKE_EXE; }
std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// A small scene that bakes in well under a second (coupled induction, a kinematic magnet).
const char* kScene =
    "magbake: 1\n"
    "name: pickup\n"
    "units: {length: mm, angle: deg}\n"
    "time: {fps: 30, frames: [1, 4], dt: 0.002}\n"
    "gravity: [0, 0, -9810]\n"
    "magnetics: {quality: draft, induction: coupled}\n"
    "materials:\n"
    "  N42: {kind: permanent, remanence: 1.3, density: 7500}\n"
    "  steel: {kind: soft, chi: 700, density: 7850}\n"
    "bodies:\n"
    "  - {name: ball, shape: {sphere: {radius: 4}}, material: steel, position: [0, 0, 4]}\n"
    "  - {name: magnet, shape: {cylinder: {radius: 5, height: 8}}, material: N42, magnetization: [0, 0, 1],\n"
    "     position: [0, 0, 20], motion: kinematic}\n";

class Hostile : public ::testing::Test {
 protected:
  fs::path dir;
  void SetUp() override {
    dir = fresh_temp_dir("magbake_hostile_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir);
  }
  // Writes `text` as a scene file in the test folder.
  fs::path scene(const std::string& name, const std::string& text) {
    const fs::path p = dir / name;
    std::ofstream(p) << text;
    return p;
  }
  // A baked cache of kScene (frames 1-4).
  fs::path good_cache() {
    const fs::path out = dir / "good";
    const Outcome r = sh(exe() + " -q bake " + q(scene("pickup.yaml", kScene)) + " -o " + q(out));
    EXPECT_EQ(r.code, 0) << r.out;
    return out / "pickup.h5";
  }
};

// The scene's text with `key: value` lines replaced or appended.
std::string with(const std::string& base, const std::string& from, const std::string& to) {
  std::string s = base;
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// Every command ended by exit(), not by a signal (sh gives -1 then, or 128+N from the shell).
void expect_clean_exit(const Outcome& r, int code, const std::string& what) {
  EXPECT_EQ(r.code, code) << what << "\n" << r.out;
  EXPECT_EQ(r.out.find("Segmentation"), std::string::npos) << what;
  EXPECT_EQ(r.out.find("terminate called"), std::string::npos) << what << "\n" << r.out;
}

// Every file under `folder` (recursively) whose name ends with `ext`.
std::vector<fs::path> files_with(const fs::path& folder, const std::string& ext) {
  std::vector<fs::path> out;
  if (!fs::exists(folder)) return out;
  for (const auto& e : fs::recursive_directory_iterator(folder)) {
    if (e.is_regular_file() && e.path().string().ends_with(ext)) out.push_back(e.path());
  }
  return out;
}

// ---- patterns ---------------------------------------------------------------------------------

TEST_F(Hostile, OutputPatternsAreNeverFormatStrings) {
  // In a scene: refused at validation with the key and its line.
  for (const std::string& bad : std::vector<std::string>{"out/%s%s%s.vdb", "out/%n.vdb", "out/%x.vdb", "out/%4d.vdb", "out/####.%04d.vdb",
                                "out/f." + std::string(40, '#') + ".vdb"}) {
    const fs::path s = scene("p.yaml", std::string(kScene) + "outputs:\n  field: {path: '" + bad + "'}\n");
    const Outcome r = sh(exe() + " check --trial 0 " + q(s));
    expect_clean_exit(r, 2, bad);
    EXPECT_NE(r.out.find("outputs.field.path"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("p.yaml:"), std::string::npos) << r.out;
  }
  // On the command line: refused before any work, nothing written.
  const fs::path cache = good_cache();
  for (const std::string& bad : std::vector<std::string>{"%s%s%s.vdb", "%n%n.vdb", std::string(40, '#') + ".vdb"}) {
    const Outcome f = sh(exe() + " field " + q(cache) + " -o " + q(dir / "vol" / bad));
    expect_clean_exit(f, 2, bad);
    EXPECT_NE(f.out.find("output pattern"), std::string::npos) << f.out;
    const Outcome p = sh(exe() + " preview " + q(cache) + " -o " + q(dir / "img" / bad));
    expect_clean_exit(p, 2, bad);
  }
  EXPECT_FALSE(fs::exists(dir / "vol"));
  // Legal patterns expand as documented: ####, %04d, %d, %% and none.
  const Outcome ok = sh(exe() + " -q field " + q(cache) + " --frames 2-2 --voxel 0.004 -o " + q(dir / "v" / "a%%b.%03d.vdb"));
  EXPECT_EQ(ok.code, 0) << ok.out;
  EXPECT_TRUE(fs::exists(dir / "v" / "a%b.002.vdb"));
}

TEST_F(Hostile, APatternStoredInACacheIsCheckedToo) {
  const fs::path cache = good_cache();
  // Rewrite the scene text inside the cache with a format-string pattern (as an older or
  // hand-edited cache could hold), then export without -o.
  const std::string text = std::string(kScene) + "outputs:\n  field: {path: 'out/%s%s%s%n.vdb'}\n";
  {
    const hid_t f = H5Fopen(cache.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    ASSERT_GE(H5Ldelete(f, "parameters/scene_text", H5P_DEFAULT), 0);
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, text.size());
    const hsize_t n = 1;
    const hid_t space = H5Screate_simple(1, &n, nullptr);
    const hid_t d = H5Dcreate2(f, "parameters/scene_text", type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, text.data()), 0);
    H5Dclose(d), H5Sclose(space), H5Tclose(type), H5Fclose(f);
  }
  const Outcome r = sh("cd " + q(dir) + " && " + exe() + " field " + q(cache) + " --voxel 0.004");
  expect_clean_exit(r, 2, "stored pattern");
  EXPECT_NE(r.out.find("do not validate"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "out"));
  // With -o the stored outputs are ignored (with a warning) and the export works.
  const Outcome w = sh(exe() + " field " + q(cache) + " --frames 1-1 --voxel 0.004 -o " + q(dir / "v" / "f.####.vdb"));
  EXPECT_EQ(w.code, 0) << w.out;
  EXPECT_NE(w.out.find("ignored"), std::string::npos) << w.out;
  EXPECT_TRUE(fs::exists(dir / "v" / "f.0001.vdb"));
}

// ---- numbers ----------------------------------------------------------------------------------

TEST_F(Hostile, NumbersThatOverflowAreErrorsAtTheirKey) {
  struct Case {
    std::string from, to, key;
  };
  const std::vector<Case> cases = {
      {"frames: [1, 4]", "frames: [1, 3e9]", "time.frames"},
      {"frames: [1, 4]", "frames: [-2e9, 4]", "time.frames"},
      {"dt: 0.002", "dt: 1e-300", "time.dt"},
      {"fps: 30", "fps: 1e-10", "time.fps"},
      {"remanence: 1.3", "remanence: 1e308", "remanence"},
      {"chi: 700", "chi: 1e300", "chi"},
      {"density: 7850", "density: 1e300", "density"},
      {"radius: 4}", "radius: 1e300}", "radius"},
      {"position: [0, 0, 4]", "position: [0, 0, 1e300]", "position"},
      {"gravity: [0, 0, -9810]", "gravity: [0, 0, -1e300]", "gravity"},
      {"quality: draft,", "quality: draft, cell_size: 1e-12,", "magnetics.cell_size"},
      {"quality: draft,", "quality: draft, surface_tolerance: 1e-12,", "magnetics.surface_tolerance"},
      {"quality: draft,", "quality: draft, surface_tolerance: -1,", "magnetics.surface_tolerance"},
      {"quality: draft,", "quality: draft, grading: 4,", "magnetics.grading"},
      {"quality: draft,", "quality: draft, grading: 0.5,", "magnetics.grading"},
      {"quality: draft,", "quality: draft, soft_cells_across: 0,", "magnetics.soft_cells_across"},
      {"quality: draft,", "quality: draft, soft_cells_across: 6.5,", "magnetics.soft_cells_across"},
      {"quality: draft,", "quality: draft, soft_cells_across: 1e9,", "magnetics.soft_cells_across"},
  };
  for (const Case& c : cases) {
    const fs::path s = scene("n.yaml", with(kScene, c.from, c.to));
    for (const std::string cmd : {"check --trial 0", "eval", "bake"}) {
      const Outcome r = sh(exe() + " " + cmd + " " + q(s) + (cmd == "bake" ? " -o " + q(dir / "o") : ""));
      expect_clean_exit(r, 2, c.to + " / " + cmd);
      EXPECT_NE(r.out.find(c.key), std::string::npos) << c.to << "\n" << r.out;
    }
  }
  const fs::path every = scene("e.yaml", std::string(kScene) + "outputs:\n  field: {path: 'f.####.vdb', every: 1e30}\n");
  expect_clean_exit(sh(exe() + " check --trial 0 " + q(every)), 2, "every 1e30");
  EXPECT_FALSE(fs::exists(dir / "o"));
}

TEST_F(Hostile, ACellSizeTinyAgainstTheBodyIsAClearErrorNotACrash) {
  // 2.4e-7 m cells on a 1 m box: 7e19 cells, once an int64 overflow that passed the budget.
  const std::string text =
      "magbake: 1\nunits: {length: m, angle: deg}\ntime: {fps: 24, frames: [1, 2]}\nmagnetics: {cell_size: 2.4e-7}\n"
      "materials:\n  n42: {kind: permanent, remanence: 1.3, density: 7500}\n"
      "bodies:\n  - {name: big, shape: {box: [1, 1, 1]}, material: n42, magnetization: [0, 0, 1]}\n";
  const fs::path s = scene("tiny.yaml", text);
  for (const std::string cmd : {"check --trial 0", "eval", "probe --at 2,0,0", "bake"}) {
    const Outcome r = sh(exe() + " " + cmd + " " + q(s) + (cmd == "bake" ? " -o " + q(dir / "o") : ""));
    expect_clean_exit(r, 2, cmd);
    EXPECT_NE(r.out.find("grid cells"), std::string::npos) << cmd << "\n" << r.out;
  }
}

TEST_F(Hostile, CommandLineNumbersAreChecked) {
  const fs::path cache = good_cache();
  const std::string field = exe() + " field " + q(cache) + " -o " + q(dir / "v" / "f.####.vdb") + " ";
  for (const std::string args : {"--voxel 1e-300", "--voxel -1", "--voxel nan", "--voxel inf", "--margin nan",
                                 "--margin -1", "--threshold nan", "--threshold -1", "--theta nan", "--theta -1",
                                 "--bounds 0,0,0,inf,1,1", "--bounds nan,0,0,1,1,1", "--bounds 0,0,0,1,1,1junk",
                                 "--bounds 1,1,1,0,0,0", "--voxel 1e-7"}) {
    expect_clean_exit(sh(field + args), 2, args);
  }
  EXPECT_TRUE(files_with(dir / "v", ".vdb").empty());
  const std::string preview = exe() + " preview " + q(cache) + " -o " + q(dir / "p" / "p.####.png") + " ";
  for (const std::string args : {"--size 0x0", "--size 100x100junk", "--size -5x100", "--size 99999999x1"}) {
    expect_clean_exit(sh(preview + args), 2, args);
  }
  const fs::path s = scene("s.yaml", kScene);
  for (const std::string& args : std::vector<std::string>{"eval --time nan", "eval --time 1e300", "probe --at 0,0,0 --time inf",
                                 "--threads -3 eval", "check --trial nan", "diff " + q(cache) + " " + q(cache) + " --atol nan"}) {
    const bool has_scene = args.rfind("diff", 0) != 0;
    expect_clean_exit(sh(exe() + " " + args + (has_scene ? " " + q(s) : "")), 2, args);
  }
}

// ---- files that are not what they seem --------------------------------------------------------

TEST_F(Hostile, AFifoIsNeverReadAsAMeshOrScene) {
  const fs::path fifo = dir / "mesh.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  const fs::path s = scene("fifo.yaml", with(kScene, "shape: {sphere: {radius: 4}}", "shape: {mesh: {file: mesh.obj}}"));
  const Outcome r = sh("timeout 20 " + exe() + " check --trial 0 " + q(s));
  expect_clean_exit(r, 2, "mesh fifo");
  EXPECT_NE(r.out.find("not a regular file"), std::string::npos) << r.out;
  const Outcome t = sh("timeout 20 " + exe() + " check --trial 0 " + q(fifo));
  expect_clean_exit(t, 2, "scene fifo");
  const Outcome p = sh("timeout 20 " + exe() + " probe " + q(scene("s.yaml", kScene)) + " --points " + q(fifo));
  expect_clean_exit(p, 2, "points fifo");
}

TEST_F(Hostile, ScenePathsStayInsideTheOutputFolder) {
  const fs::path work = dir / "work";
  fs::create_directories(work);
  const std::string in_work = "cd " + q(work) + " && " + exe() + " ";
  const std::string esc = "escaped_" + dir.filename().string();  // unique: /tmp is shared
  // A name that is a path.
  const fs::path named = scene("named.yaml", with(kScene, "name: pickup", "name: ../../" + esc));
  Outcome r = sh(in_work + "bake " + q(named));
  expect_clean_exit(r, 2, "name ../../escaped");
  EXPECT_NE(r.out.find("name"), std::string::npos) << r.out;
  // Output paths with '..'.
  for (const std::string& out : std::vector<std::string>{"cache: ../" + esc + ".h5", "cache: a/../../" + esc + ".h5",
                                                         "field: {path: '../f.####.vdb'}",
                                                         "preview: {path: 'x/../../p.####.png'}"}) {
    r = sh(in_work + "bake " + q(scene("dots.yaml", std::string(kScene) + "outputs:\n  " + out + "\n")));
    expect_clean_exit(r, 2, out);
    EXPECT_NE(r.out.find("leaves the output folder"), std::string::npos) << out << "\n" << r.out;
  }
  // Absolute paths only when asked for.
  const fs::path abs = dir / "abs" / "shot.h5";
  const fs::path absolute = scene("abs.yaml", std::string(kScene) + "outputs:\n  cache: " + abs.string() + "\n");
  r = sh(in_work + "bake " + q(absolute));
  expect_clean_exit(r, 2, "absolute cache path");
  EXPECT_NE(r.out.find("--allow-absolute-outputs"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(abs));
  r = sh(in_work + "-q bake --allow-absolute-outputs " + q(absolute));
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(abs));
  // Nothing was written outside the working folder by the refused bakes.
  EXPECT_FALSE(fs::exists(dir / (esc + ".h5")));
  EXPECT_FALSE(fs::exists(dir.parent_path() / (esc + ".h5")));
  EXPECT_FALSE(fs::exists(dir.parent_path().parent_path() / (esc + ".h5")));
  EXPECT_FALSE(fs::exists(dir / "f.0001.vdb"));
}

// ---- caches -----------------------------------------------------------------------------------

// Every dataset of a cache, by path.
std::vector<std::string> datasets(const fs::path& cache) {
  std::vector<std::string> out;
  const hid_t f = H5Fopen(cache.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  H5Ovisit(
      f, H5_INDEX_NAME, H5_ITER_NATIVE,
      [](hid_t, const char* name, const H5O_info_t* info, void* data) -> herr_t {
        if (info->type == H5O_TYPE_DATASET) static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &out);
  H5Fclose(f);
  return out;
}

// Runs info, diff, field and preview on a damaged cache: each must exit 0 or `code`, never
// crash; returns the codes of field and preview.
std::pair<int, int> use_damaged(const fs::path& bad, const fs::path& good, const fs::path& out, const std::string& what) {
  const Outcome info = sh(exe() + " info " + q(bad));
  EXPECT_TRUE(info.code == 0 || info.code == 2) << what << "\n" << info.out;
  const Outcome diff = sh(exe() + " diff " + q(good) + " " + q(bad));
  EXPECT_TRUE(diff.code == 0 || diff.code == 1 || diff.code == 2) << what << "\n" << diff.out;
  const Outcome field = sh(exe() + " -q field " + q(bad) + " --frames 1-1 --voxel 0.004 -o " + q(out / "f.####.vdb"));
  EXPECT_TRUE(field.code == 0 || field.code == 2) << what << "\n" << field.out;
  const Outcome preview =
      sh(exe() + " -q preview " + q(bad) + " --frames 1-1 --size 32x32 --no-field-lines -o " + q(out / "p.####.png"));
  EXPECT_TRUE(preview.code == 0 || preview.code == 2) << what << "\n" << preview.out;
  for (const Outcome* o : {&info, &diff, &field, &preview}) {
    EXPECT_EQ(o->out.find("terminate called"), std::string::npos) << what << "\n" << o->out;
  }
  return {field.code, preview.code};
}

// Copies `good` to `bad` and applies `edit` to the copy, opened read-write.
template <class Edit>
void damage(const fs::path& good, const fs::path& bad, Edit edit) {
  fs::copy_file(good, bad, fs::copy_options::overwrite_existing);
  const hid_t f = H5Fopen(bad.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  edit(f);
  H5Fclose(f);
}

// Overwrites element `index` of an integer or float dataset with `value`.
void poke(hid_t f, const std::string& path, hsize_t index, double value) {
  const hid_t d = H5Dopen2(f, path.c_str(), H5P_DEFAULT);
  ASSERT_GE(d, 0) << path;
  const hid_t space = H5Dget_space(d);
  const int rank = H5Sget_simple_extent_ndims(space);
  std::vector<hsize_t> dims(rank);
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  std::vector<hsize_t> at(rank, 0);
  hsize_t rest = index;
  for (int k = rank - 1; k >= 0; --k) at[k] = rest % dims[k], rest /= dims[k];
  H5Sselect_elements(space, H5S_SELECT_SET, 1, at.data());
  const hsize_t one = 1;
  const hid_t mem = H5Screate_simple(1, &one, nullptr);
  const hid_t type = H5Dget_type(d);
  if (H5Tget_class(type) == H5T_INTEGER) {
    const long long v = static_cast<long long>(value);
    EXPECT_GE(H5Dwrite(d, H5T_NATIVE_LLONG, mem, space, H5P_DEFAULT, &v), 0) << path;
  } else {
    EXPECT_GE(H5Dwrite(d, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, &value), 0) << path;
  }
  H5Tclose(type), H5Sclose(mem), H5Sclose(space), H5Dclose(d);
}

// Replaces a dataset by one with one row fewer (a short array).
void shorten(hid_t f, const std::string& path) {
  const hid_t d = H5Dopen2(f, path.c_str(), H5P_DEFAULT);
  const hid_t space = H5Dget_space(d), type = H5Dget_type(d);
  const int rank = H5Sget_simple_extent_ndims(space);
  std::vector<hsize_t> dims(rank);
  H5Sget_simple_extent_dims(space, dims.data(), nullptr);
  if (rank == 0 || dims[0] == 0) {
    H5Tclose(type), H5Sclose(space), H5Dclose(d);
    return;
  }
  hsize_t total = 1;
  for (hsize_t x : dims) total *= x;
  std::vector<char> buf(total * H5Tget_size(type));
  H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
  H5Dclose(d), H5Sclose(space);
  H5Ldelete(f, path.c_str(), H5P_DEFAULT);
  dims[0] -= 1;
  const hid_t s2 = H5Screate_simple(rank, dims.data(), nullptr);
  const hid_t d2 = H5Dcreate2(f, path.c_str(), type, s2, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (dims[0] > 0) H5Dwrite(d2, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf.data());
  H5Dclose(d2), H5Sclose(s2), H5Tclose(type);
}

// The datasets the readers need: without any of them, field and preview must refuse the cache.
const char* kRequired[] = {"bodies/name",
                           "bodies/center_of_mass",
                           "frames/step",
                           "frames/time",
                           "particles/bodies/position/value",
                           "particles/bodies/orientation/value",
                           "magnetics/cells/body",
                           "magnetics/cells/part",
                           "magnetics/cells/half",
                           "magnetics/parts/orientation",
                           "magnetics/induced_cells",
                           "magnetics/induced_moment/value",
                           "geometry/vertices",
                           "geometry/triangles",
                           "geometry/submesh_vertex_count",
                           "geometry/submesh_triangle_begin",
                           "parameters/scene_text",
                           "bake/frames_done"};

TEST_F(Hostile, CachesMissingOrShortOfAnyDatasetAreRefusedNotCrashedOn) {
  const fs::path good = good_cache(), bad = dir / "bad.h5", out = dir / "out";
  const std::vector<std::string> all = datasets(good);
  ASSERT_GT(all.size(), 40u);
  int refused = 0, variants = 0;
  for (const std::string& path : all) {
    for (const bool remove : {true, false}) {
      damage(good, bad, [&](hid_t f) {
        if (remove) H5Ldelete(f, path.c_str(), H5P_DEFAULT);
        else shorten(f, path);
      });
      const std::string what = (remove ? "without " : "short ") + path;
      const auto [field, preview] = use_damaged(bad, good, out, what);
      ++variants;
      refused += field == 2;
      for (const char* r : kRequired) {
        // A per-frame series one row short is a cache with one complete frame fewer (as a
        // killed bake leaves): readable. Every other short array must be refused.
        const bool series = path.starts_with("frames/") || path.starts_with("particles/") ||
                            path.starts_with("magnetics/induced_moment") || path.starts_with("bake/");
        if (path == r && (remove || !series)) {
          EXPECT_EQ(field, 2) << what;
          EXPECT_EQ(preview, 2) << what;
        }
      }
    }
  }
  // Attributes the readers use.
  for (const char* attr : {"fps", "first_frame", "near_field", "external_field", "scene_hash", "scene_name"}) {
    damage(good, bad, [&](hid_t f) {
      const hid_t p = H5Gopen2(f, "parameters", H5P_DEFAULT);
      H5Adelete(p, attr);
      H5Gclose(p);
    });
    const auto [field, preview] = use_damaged(bad, good, out, std::string("without @") + attr);
    EXPECT_EQ(field, 2) << attr;
    EXPECT_EQ(preview, 2) << attr;
    ++variants;
  }
  std::printf("%d damaged caches, field refused %d\n", variants, refused);
  EXPECT_GE(variants, 140);  // every dataset and attribute, missing and short (142 on 2026-12-03)
}

TEST_F(Hostile, CachesWithIndicesOutOfRangeOrBadFramesAreRefused) {
  const fs::path good = good_cache(), bad = dir / "bad.h5", out = dir / "out";
  struct Case {
    const char* path;
    hsize_t index;
    double value;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Case> cases = {
      {"magnetics/cells/body", 0, 999},          {"magnetics/cells/body", 0, -1},
      {"magnetics/cells/part", 3, 999},          {"magnetics/parts/body", 0, 77},
      {"magnetics/induced_cells", 0, 1e12},      {"magnetics/induced_cells", 1, -4},
      {"geometry/submesh_body", 0, 12},          {"geometry/submesh_vertex_count", 0, 1e15},
      {"geometry/submesh_vertex_begin", 1, -5},  {"geometry/submesh_triangle_count", 0, 4e18},
      {"geometry/triangles", 5, 1e9},            {"geometry/triangles", 0, -1},
      {"geometry/vertices", 0, nan},             {"magnetics/cells/half", 2, 0},
      {"geometry/submesh_color", 1, 2},          {"geometry/submesh_color", 0, nan},
      {"magnetics/cells/volume", 2, -1},         {"magnetics/cells/position", 0, nan},
      {"magnetics/parts/orientation", 0, 0},     {"frames/step", 2, 1},
      {"frames/step", 1, 1},                     {"bodies/center_of_mass", 0, nan},
      {"bake/status", 0, 99},                    {"magnetics/cells/ball", 1, 7},
      {"magnetics/parts/surface_begin", 1, 1e9}, {"magnetics/parts/surface_begin", 0, 3},
      {"magnetics/parts/surface_vertex", 4, nan},
  };
  for (const Case& c : cases) {
    damage(good, bad, [&](hid_t f) {
      poke(f, c.path, c.index, c.value);
      if (std::string(c.path) == "magnetics/parts/orientation") {
        for (hsize_t k = 1; k < 4; ++k) poke(f, c.path, k, 0);
      }
    });
    const std::string what = std::string(c.path) + "[" + std::to_string(c.index) + "] = " + std::to_string(c.value);
    const auto [field, preview] = use_damaged(bad, good, out, what);
    EXPECT_EQ(field, 2) << what;
    EXPECT_EQ(preview, 2) << what;
  }
  // frames_done larger than what the series hold: only the frames every series holds are read.
  damage(good, bad, [&](hid_t f) { poke(f, "bake/frames_done", 0, 1e12); });
  const Outcome info = sh(exe() + " info " + q(bad));
  EXPECT_EQ(info.code, 0) << info.out;
  EXPECT_NE(info.out.find("4 frames"), std::string::npos) << info.out;
}

TEST_F(Hostile, ACorruptSuperblockIsRefusedAtOnce) {
  // A checksum failure in the file's first metadata once made the SWMR reader retry 100 times
  // with growing sleeps (minutes per command; found by fuzz/cache_fuzzer).
  const fs::path good = good_cache(), bad = dir / "bad.h5";
  for (const int offset : {12, 24, 40, 44, 47}) {
    fs::copy_file(good, bad, fs::copy_options::overwrite_existing);
    {
      std::fstream f(bad, std::ios::in | std::ios::out | std::ios::binary);
      f.seekg(offset);
      const char c = static_cast<char>(f.get() ^ 0x5a);
      f.seekp(offset);
      f.put(c);
    }
    const auto t0 = std::chrono::steady_clock::now();
    const Outcome r = sh("timeout 60 " + exe() + " info " + q(bad));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_TRUE(r.code == 2 || r.code == 0) << offset << "\n" << r.out;
    EXPECT_LT(seconds, 10) << "byte " << offset;
  }
}

TEST_F(Hostile, NonFinitePosesAreNeverTheSameAndNeverExported) {
  const fs::path good = good_cache(), bad = dir / "nan.h5", out = dir / "out";
  for (const double v : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    damage(good, bad, [&](hid_t f) { poke(f, "particles/bodies/position/value", 2 * 2 * 3, v); });  // frame 3, ball x
    damage(good, dir / "nan2.h5", [&](hid_t f) { poke(f, "particles/bodies/position/value", 2 * 2 * 3, v); });
    for (const std::string mode : {"", "--exact "}) {
      const Outcome d = sh(exe() + " diff " + mode + q(bad) + " " + q(dir / "nan2.h5"));
      EXPECT_EQ(d.code, 1) << mode << d.out;
      EXPECT_NE(d.out.find("non-finite"), std::string::npos) << d.out;
    }
    const Outcome f = sh(exe() + " field " + q(bad) + " --voxel 0.004 -o " + q(out / "f.####.vdb"));
    EXPECT_EQ(f.code, 2) << f.out;
    EXPECT_NE(f.out.find("non-finite"), std::string::npos) << f.out;
  }
}

// ---- outputs complete or absent --------------------------------------------------------------

TEST_F(Hostile, AFullDiskLeavesNoIncompleteFileUnderAFinalName) {
  // A file-size limit (ulimit -f, SIGXFSZ ignored) makes every write past it fail with EFBIG,
  // as a full disk does with ENOSPC, for any user and without mounting anything.
  const fs::path cache = good_cache();
  const std::string limited = "trap '' XFSZ; ulimit -f 40; ";  // 40 KiB per file
  const fs::path vol = dir / "vol";
  const Outcome f = sh(limited + exe() + " -q field " + q(cache) + " --frames 1-2 --voxel 0.001 -o " + q(vol / "f.####.vdb"));
  EXPECT_EQ(f.code, 1) << f.out;
  EXPECT_NE(f.out.find("cannot write"), std::string::npos) << f.out;
  EXPECT_TRUE(files_with(vol, ".vdb").empty());
  EXPECT_TRUE(files_with(vol, ".tmp").empty() && fs::is_empty(vol));
  // Previews: a PNG larger than the limit.
  const fs::path img = dir / "img";
  const Outcome p = sh("trap '' XFSZ; ulimit -f 2; " + exe() + " -q preview " + q(cache) + " --frames 1-2 --size 1024x1024 -o " +
                       q(img / "p.####.png"));
  EXPECT_EQ(p.code, 1) << p.out;
  EXPECT_TRUE(files_with(img, ".png").empty());
  // A cache that cannot be created: an error, no crash, and no final-named cache.
  const fs::path out = dir / "bake";
  const Outcome b = sh("trap '' XFSZ; ulimit -f 8; " + exe() + " -q bake " + q(scene("b.yaml", kScene)) + " -o " + q(out));
  EXPECT_EQ(b.code, 1) << b.out;
  EXPECT_FALSE(fs::exists(out / "pickup.h5"));
  EXPECT_EQ(b.out.find("Segmentation"), std::string::npos) << b.out;
}

TEST_F(Hostile, TwoBakesOfOneCacheAtOnceCannotBothWrite) {
  // A bake of a few seconds, and a second one into the same folder while it runs.
  const std::string longer = with(kScene, "frames: [1, 4], dt: 0.002", "frames: [1, 120], dt: 0.0005");
  const fs::path s = scene("long.yaml", longer), out = dir / "o";
  std::thread first([&] {
    const Outcome a = sh(exe() + " -q bake " + q(s) + " -o " + q(out));
    EXPECT_EQ(a.code, 0) << a.out;
  });
  for (int i = 0; i < 2000 && !fs::exists(out / "pickup.h5.lock"); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_TRUE(fs::exists(out / "pickup.h5.lock"));  // (no ASSERT: the thread must be joined)
  const Outcome second = sh(exe() + " -q bake " + q(s) + " -o " + q(out));
  const Outcome resumed = sh(exe() + " -q bake --resume " + q(s) + " -o " + q(out));
  first.join();
  EXPECT_EQ(second.code, 1) << second.out;
  EXPECT_NE(second.out.find("another magbake process"), std::string::npos) << second.out;
  EXPECT_EQ(resumed.code, 1) << resumed.out;
  // The first bake's cache is complete and readable; the lock is gone.
  const Outcome info = sh(exe() + " info " + q(out / "pickup.h5"));
  EXPECT_EQ(info.code, 0) << info.out;
  EXPECT_NE(info.out.find("complete, 120 frames"), std::string::npos) << info.out;
  EXPECT_FALSE(fs::exists(out / "pickup.h5.lock"));
}

}  // namespace
}  // namespace magbake::testing
