// The magbake binary's query commands (check, eval, probe, info) through real scene files,
// against the closed forms the library tests use.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "support/closed_forms.h"

using Quat = Eigen::Quaterniond;

namespace magbake::testing {
namespace {

struct Outcome {
  int code = -1;
  std::string out;
};

// Runs magbake with `args` (stderr discarded unless asked), returns exit code and stdout.
Outcome magbake(const std::string& args, bool keep_stderr = false) {
  const std::string cmd = std::string(MAGBAKE_EXE) + " " + args + (keep_stderr ? " 2>&1" : " 2>/dev/null");
  Outcome r;
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), p)) r.out += buf.data();
  const int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

std::string scene(const std::string& name) { return std::string(MAGBAKE_SOURCE_DIR) + "/scenes/" + name; }

Vec3 vec(const nlohmann::json& j) { return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>()); }

std::string temp_scene(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("magbake_cli_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path) << text;
  return path.string();
}

std::string read(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(EvalCommand, CubePairMatchesAkounYonnet) {
  const Outcome r = magbake("eval " + scene("validation/cube_pair.yaml") + " --json");
  ASSERT_EQ(r.code, 0);
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["bodies"].size(), 2u);
  EXPECT_EQ(j["bodies"][1]["name"], "upper");
  const double exact = akoun_yonnet_force(1, 1, Vec3::Constant(0.005), Vec3::Constant(0.005), Vec3(0, 0, 0.015))[2];
  const Vec3 F = vec(j["bodies"][1]["force"]);
  EXPECT_NEAR(F[2], exact, 1.5e-3 * std::abs(exact));  // README: 6.5731 against 6.5683 N (0.073%)
  EXPECT_LT((F + vec(j["bodies"][0]["force"])).norm(), 1e-12 * F.norm());
  EXPECT_GT(j["cells"].get<int>(), 0);
  EXPECT_TRUE(j["induction"].contains("iterations"));
  EXPECT_TRUE(j["induction"].contains("residual"));
  for (const char* key : {"force", "torque", "moment"}) EXPECT_EQ(j["bodies"][0][key].size(), 3u);
}

TEST(EvalCommand, SoftSphereInFieldHasTheExactMoment) {
  const Outcome r = magbake("eval " + scene("validation/sphere_in_field.yaml") + " --json");
  ASSERT_EQ(r.code, 0);
  const auto j = nlohmann::json::parse(r.out);
  const double R = 0.005;
  const double exact = 4 * std::acos(-1.0) * R * R * R * 700.0 / 703.0 * 0.01 / (4e-7 * std::acos(-1.0));
  EXPECT_NEAR(vec(j["bodies"][0]["moment"])[2], exact, 0.01 * exact);
  EXPECT_GT(j["induction"]["iterations"].get<int>(), 0);
  EXPECT_LT(j["induction"]["residual"].get<double>(), 1e-4);  // the default preset's induction tolerance
}

// The saturating-steel example (format 1.1) as its comment states it: at 2 mm from its magnet
// the linear ball's weight (6.55 N) is lifted and the saturating one's is not; eval --json
// reports the Newton steps, check --json the material's saturation.
TEST(EvalCommand, SaturatingSteelExampleHoldsWhatItsCommentSays) {
  const Outcome r = magbake("eval " + scene("format11/saturating_steel.yaml") + " --time 1.5 --json");
  ASSERT_EQ(r.code, 0);
  const auto j = nlohmann::json::parse(r.out);
  double linear = 0, saturating = 0;
  for (const auto& b : j["bodies"]) {
    if (b["name"] == "weight_linear") linear = vec(b["force"])[2];
    if (b["name"] == "weight_saturating") saturating = vec(b["force"])[2];
  }
  const double weight = 0.6676 * 9.81;  // brass cylinder, radius 25 mm, height 40 mm, 8500 kg/m^3
  std::printf("pull at 2 mm: linear %.2f N, saturating %.2f N, weight %.2f N\n", linear, saturating, weight);
  EXPECT_GT(linear, weight);
  EXPECT_LT(saturating, 0.9 * weight);
  EXPECT_TRUE(j["induction"]["converged"].get<bool>());
  EXPECT_GE(j["induction"]["nonlinear_iterations"].get<int>(), 1);
  EXPECT_LT(j["induction"]["nonlinear_residual"].get<double>(), 1e-3);  // 10 x the default tolerance

  const Outcome c = magbake("check " + scene("format11/saturating_steel.yaml") + " --json --trial 0");
  ASSERT_EQ(c.code, 0);
  const auto cj = nlohmann::json::parse(c.out);
  bool found = false;
  for (const auto& m : cj["materials"]) {
    if (m["name"] == "ferrite") found = m["saturation_T"].get<double>() == 0.4;
  }
  EXPECT_TRUE(found) << c.out;
}

TEST(EvalAndProbe, DipolePairMatchesPointDipoles) {
  const double mu0 = 4e-7 * std::acos(-1.0);
  const double m = 1.2 / mu0 * 4.0 / 3.0 * std::acos(-1.0) * 8e-9;
  const Vec3 xa(0, 0, 0), xb(0.01, 0.003, 0.004);
  const Vec3 ma(0, 0, m);
  const Quat q(Eigen::AngleAxisd(std::acos(-1.0) / 6, Vec3::UnitZ()));
  const Vec3 mb = q * Vec3(m, 0, 0);
  // Force on b: gradient of mb . B_a by central differences of the closed-form field.
  Vec3 Fb;
  for (int k = 0; k < 3; ++k) {
    Vec3 e = Vec3::Zero();
    e[k] = 1e-7;
    Fb[k] = (mb.dot(point_dipole_field(ma, xb + e - xa)) - mb.dot(point_dipole_field(ma, xb - e - xa))) / 2e-7;
  }
  const Outcome r = magbake("eval " + scene("validation/dipole_pair.yaml") + " --json");
  ASSERT_EQ(r.code, 0);
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_LT((vec(j["bodies"][1]["force"]) - Fb).norm(), 1e-5 * Fb.norm());
  EXPECT_LT((vec(j["bodies"][1]["torque"]) - mb.cross(point_dipole_field(ma, xb - xa))).norm(),
            1e-5 * mb.norm() * point_dipole_field(ma, xb - xa).norm());
  // probe: B at two points from both dipoles.
  const Outcome p = magbake("probe " + scene("validation/dipole_pair.yaml") + " --at 0.02,0,0 --at=-0.01,0.01,0.005 --json");
  ASSERT_EQ(p.code, 0);
  const auto jp = nlohmann::json::parse(p.out);
  ASSERT_EQ(jp["B"].size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const Vec3 x = vec(jp["points"][i]);
    const Vec3 ref = point_dipole_field(ma, x - xa) + point_dipole_field(mb, x - xb);
    EXPECT_LT((vec(jp["B"][i]) - ref).norm(), 1e-9 * ref.norm()) << i;
  }
}

TEST(ProbeCommand, CubePairFieldMatchesFurlaniAndReadsPointFiles) {
  const std::string pts = temp_scene("points.txt", "# x y z (m)\n0.003 0.001 0.0215\n0.02,0.0,0.0075\n\n0 0 -0.02\n");
  const Outcome r = magbake("probe " + scene("validation/cube_pair.yaml") + " --points " + pts + " --json");
  ASSERT_EQ(r.code, 0);
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["B"].size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const Vec3 x = vec(j["points"][i]);
    const Vec3 ref = furlani_cuboid_field(1.0, Vec3::Constant(0.005), x) +
                     furlani_cuboid_field(1.0, Vec3::Constant(0.005), x - Vec3(0, 0, 0.015));
    EXPECT_LT((vec(j["B"][i]) - ref).norm(), 1e-3 * ref.norm()) << x.transpose();
  }
  const std::string bad = temp_scene("bad_points.txt", "0 0\n");
  const Outcome e = magbake("probe " + scene("validation/cube_pair.yaml") + " --points " + bad, true);
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.out.find("bad_points.txt:1:"), std::string::npos) << e.out;
}

// The quality presets trade time for accuracy as docs/scene-format.md documents (cube pair,
// 1 mm gap): draft within 1%, default within 0.2%, high within 0.01%.
TEST(EvalCommand, QualityPresetsChangeTheErrorAsDocumented) {
  const double exact = akoun_yonnet_force(1, 1, Vec3::Constant(0.005), Vec3::Constant(0.005), Vec3(0, 0, 0.011))[2];
  std::string text = read(scene("validation/cube_pair.yaml"));
  text = std::regex_replace(text, std::regex("position: \\[0, 0, 15\\]"), "position: [0, 0, 11]");
  double previous = 1;
  for (auto [q, bound] : {std::pair{"draft", 0.01}, {"default", 0.002}, {"high", 1e-4}}) {
    const std::string t = std::regex_replace(text, std::regex("quality: default"), std::string("quality: ") + q);
    const Outcome r = magbake("eval " + temp_scene(std::string("q_") + q + ".yaml", t) + " --json");
    ASSERT_EQ(r.code, 0) << q;
    const double err = std::abs(vec(nlohmann::json::parse(r.out)["bodies"][1]["force"])[2] / exact - 1);
    EXPECT_LT(err, bound) << q;
    EXPECT_LT(err, previous) << q;
    previous = err;
  }
}

TEST(EvalCommand, SameSceneInMetresAndMillimetresGivesTheSameForces) {
  const std::string mm = read(scene("validation/cube_pair.yaml"));
  std::string m = std::regex_replace(mm, std::regex("length: mm"), "length: m");
  m = std::regex_replace(m, std::regex("\\[10, 10, 10\\]"), "[0.01, 0.01, 0.01]");
  m = std::regex_replace(m, std::regex("\\[0, 0, 15\\]"), "[0, 0, 0.015]");
  const auto a = nlohmann::json::parse(magbake("eval " + scene("validation/cube_pair.yaml") + " --json").out);
  const auto b = nlohmann::json::parse(magbake("eval " + temp_scene("metres.yaml", m) + " --json").out);
  for (int i = 0; i < 2; ++i) {
    const Vec3 fa = vec(a["bodies"][i]["force"]), fb = vec(b["bodies"][i]["force"]);
    EXPECT_LT((fa - fb).norm(), 1e-9 * fa.norm());
  }
}

TEST(Commands, InvalidSceneExitsTwoWithPositionsAndNothingOnStdout) {
  const std::string bad = temp_scene("bad.yaml", "magbake: 1\nunits: {length: mm, angle: deg}\nbodies:\n  - {name: a}\n");
  const Outcome r = magbake("eval " + bad + " --json");
  EXPECT_EQ(r.code, 2);
  EXPECT_TRUE(r.out.empty());
  const Outcome e = magbake("check " + bad, true);
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.out.find("bad.yaml:4:5: bodies[0]: missing required key 'shape'"), std::string::npos) << e.out;
}

TEST(Commands, CheckAndInfoSummarizeTheDemo) {
  const Outcome c = magbake("check " + scene("demo.yaml"));
  EXPECT_EQ(c.code, 0);
  EXPECT_NE(c.out.find("cells    sphere"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("cost"), std::string::npos);
  const Outcome i = magbake("info " + scene("demo.yaml"));
  EXPECT_EQ(i.code, 0);
  EXPECT_NE(i.out.find("toy_magnet_and_sphere"), std::string::npos);
  EXPECT_EQ(magbake("--help").code, 0);
  EXPECT_EQ(magbake("eval").code, 2);             // missing scene
  EXPECT_EQ(magbake("nonsense").code, 2);         // unknown command
}

// check --json: the expected cost of the demo bake from a trial bake (here all of its 5963 steps
// of dt fit in the trial: 89 frame intervals x ceil((1/30 s) / 0.5 ms) = 67), and --trial 0.
// The trial's budget is wall time, so it is far above what the whole shot costs on any machine
// (about 3 s here; a loaded CI runner once needed 65 s): the trial ends with the shot.
TEST(Commands, CheckJsonEstimatesTheBake) {
  const Outcome c = magbake("check " + scene("demo.yaml") + " --json --trial 100000");
  ASSERT_EQ(c.code, 0) << c.out;
  const auto j = nlohmann::json::parse(c.out);
  EXPECT_EQ(j["name"], "toy_magnet_and_sphere");
  EXPECT_EQ(j["cells"], 664);  // the magnet's two inserts 2 x 128, the steel sphere 408 (8 across a soft part)
  const auto& e = j["estimate"];
  EXPECT_EQ(e["nominal_steps"], 5963);
  EXPECT_EQ(e["trial_steps"], 5963);  // the whole shot: counts are then the bake's own
  EXPECT_GE(e["substeps"].get<double>(), 5963);
  // One evaluation per substep, plus one after each wake-up of a sleeping body (a handful).
  EXPECT_GE(e["evaluations"].get<double>(), e["substeps"].get<double>());
  EXPECT_LE(e["evaluations"].get<double>(), e["substeps"].get<double>() + 20);
  EXPECT_GT(e["induction_iterations"].get<double>(), 0);
  EXPECT_GT(e["seconds"].get<double>(), 0);
  // The summary, as JSON: every body with its cells, the time and the magnetics settings.
  EXPECT_EQ(j["time"]["frame_count"], 90);
  ASSERT_EQ(j["bodies"].size(), 3u);
  int cells = 0;
  for (const auto& b : j["bodies"]) cells += b["cells"].get<int>();
  EXPECT_EQ(cells, 664);
  EXPECT_EQ(j["bodies"][1]["name"], "sphere");
  EXPECT_EQ(j["bodies"][1]["cells"], 408);
  EXPECT_EQ(j["magnetics"]["soft_cells_across"], 8);
  EXPECT_EQ(j["bodies"][1]["damping"]["linear"], 0.0);
  const Outcome none = magbake("check " + scene("demo.yaml") + " --json --trial 0");
  ASSERT_EQ(none.code, 0);
  EXPECT_EQ(nlohmann::json::parse(none.out)["estimate"]["trial_steps"], 0);
  EXPECT_EQ(magbake("check " + scene("demo.yaml") + " --trial -1").code, 2);
}

TEST(Commands, CheckOfALargeSceneFitsOnOneScreen) {
  // 60 magnets of one shape: the summary lists the first bodies and counts the rest; --verbose
  // lists all.
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("magbake_large_check_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream f(dir / "large.yaml");
  f << "magbake: 1\nname: large\nunits: {length: mm, angle: deg}\ntime: {fps: 30, frames: [1, 2]}\n"
       "materials:\n  N42: {kind: permanent, remanence: 1.3, density: 7500}\nbodies:\n";
  for (int i = 0; i < 60; ++i) {
    f << "  - {name: m" << i << ", shape: {cylinder: {radius: 4, height: 8}}, material: N42, magnetization: [0, 0, 1], "
      << "position: [" << 30 * (i % 8) << ", " << 30 * (i / 8) << ", 10], motion: static}\n";
  }
  f.close();
  const Outcome c = magbake("check " + (dir / "large.yaml").string());
  EXPECT_EQ(c.code, 0) << c.out;
  EXPECT_LE(std::count(c.out.begin(), c.out.end(), '\n'), 40) << c.out;
  EXPECT_NE(c.out.find("... and 40 more (--verbose lists every body)"), std::string::npos) << c.out;
  EXPECT_NE(c.out.find("in 60 magnetic bodies"), std::string::npos) << c.out;
  const Outcome v = magbake("-v check " + (dir / "large.yaml").string());
  EXPECT_EQ(v.code, 0);
  EXPECT_NE(v.out.find("  m59 "), std::string::npos) << v.out;
  EXPECT_EQ(v.out.find("more (--verbose"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(EvalCommand, KinematicBodiesAreAtTheirKeyedPose) {
  const auto j0 = nlohmann::json::parse(magbake("eval " + scene("demo.yaml") + " --json --time 0").out);
  const auto j1 = nlohmann::json::parse(magbake("eval " + scene("demo.yaml") + " --json --time 2.5").out);
  // The magnet's centre of mass follows the keys: 70 mm -> 34 mm.
  EXPECT_NEAR(vec(j0["bodies"][2]["center_of_mass"])[2], 0.070, 1e-12);
  EXPECT_NEAR(vec(j1["bodies"][2]["center_of_mass"])[2], 0.034, 1e-12);
  // Closer: the pull on the steel sphere is much stronger.
  EXPECT_GT(vec(j1["bodies"][1]["force"])[2], 10 * vec(j0["bodies"][1]["force"])[2]);
  EXPECT_GT(vec(j0["bodies"][1]["force"])[2], 0);
}

}  // namespace
}  // namespace magbake::testing

namespace magbake::testing {
namespace {

// A remanence that overflows the moments: eval and probe exit 1 with a message, print nothing.
TEST(Commands, NonFiniteResultsExitOneAndPrintNothing) {
  // Two soft spheres placed at the same point: their coincident cells make the induction
  // singular. eval and probe must say so and print no numbers.
  const std::string path = temp_scene(
      "coincident.yaml",
      "magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 30, frames: [1, 2], dt: 0.001}\n"
      "materials:\n  n42: {kind: permanent, remanence: 1.3, density: 7500}\n  steel: {kind: soft, chi: 700, density: 7850}\n"
      "bodies:\n  - {name: a, shape: {box: [10, 10, 10]}, material: n42, magnetization: [1, 0, 0]}\n"
      "  - {name: b, shape: {sphere: {radius: 4}}, material: steel, position: [12, 0, 0]}\n"
      "  - {name: c, shape: {sphere: {radius: 4}}, material: steel, position: [12, 0, 0]}\n");
  const Outcome e = magbake("eval " + path + " --json");
  EXPECT_EQ(e.code, 1);
  EXPECT_TRUE(e.out.empty()) << e.out;
  EXPECT_NE(magbake("eval " + path, true).out.find("non-finite"), std::string::npos);
  const Outcome p = magbake("probe " + path + " --at 0.02,0,0 --json");
  EXPECT_EQ(p.code, 1);
  EXPECT_TRUE(p.out.empty()) << p.out;
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace magbake::testing

namespace magbake::testing {
namespace {

// `magbake farm --dry-run` (docs/farm.md): the job scripts of a shot, without a scheduler.
TEST(FarmCommand, DryRunPrintsTheSimulationAndChunkedExportJobs) {
  const std::string out = (std::filesystem::temp_directory_path() / ("magbake_farm_" + std::to_string(::getpid()))).string();
  const Outcome r = magbake("farm " + scene("demo.yaml") + " -o " + out + " --chunk 20 --partition gpu --cpus 4 --dry-run");
  ASSERT_EQ(r.code, 0) << r.out;
  // Simulation: requeued on preemption, warned by SIGUSR1, resumes from its partial cache, and
  // writes the cache only (the exports are their own jobs).
  for (const std::string& want : std::vector<std::string>{"#SBATCH --job-name=toy_magnet_and_sphere-bake\n", "#SBATCH --requeue\n", "#SBATCH --signal=B:USR1@120\n",
        "#SBATCH --partition=gpu\n", "#SBATCH --cpus-per-task=4\n", "--threads 4 bake ", "--cache-only $resume",
        "if [ -e '" + out + "/demo.h5.partial' ]; then resume=--resume; fi\n", "scontrol requeue \"$SLURM_JOB_ID\"",
        "--dependency=afterok:<bake job> " + out + "/farm/field.sh"}) {
    EXPECT_NE(r.out.find(want), std::string::npos) << want << "\n" << r.out;
  }
  // Field volumes every 3rd frame: chunks of 20 become 21 so that each task starts on a frame a
  // full run writes; 90 frames -> 5 tasks. Previews: chunks of 20 -> 5 tasks.
  const std::size_t field = r.out.find("# magbake farm: field of toy_magnet_and_sphere from " + out +
                                       "/demo.h5, frames 1-90 in chunks of 21\n");
  ASSERT_NE(field, std::string::npos) << r.out;
  EXPECT_NE(r.out.rfind("#SBATCH --array=0-4\n", field), std::string::npos);
  EXPECT_NE(r.out.find("a=$(( 1 + ${SLURM_ARRAY_TASK_ID:-0} * 21 ))\nb=$(( a + 20 ))\nif [ $b -gt 90 ]; then b=90; fi\n"),
            std::string::npos);
  EXPECT_NE(r.out.find("field '" + out + "/demo.h5' --frames $a-$b -o '" + out + "/field.####.vdb'"), std::string::npos);
  EXPECT_NE(r.out.find("preview '" + out + "/demo.h5' --frames $a-$b -o '" + out + "/preview.####.png'"),
            std::string::npos);
  // The USD stage (outputs.usd) once the cache and the volumes it references are written.
  EXPECT_NE(r.out.find("export '" + out + "/demo.h5' --usd '" + out + "/demo.usda' --field '" + out + "/field.####.vdb'\n"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("--dependency=afterok:<bake job>:<field job> " + out + "/farm/usd.sh"), std::string::npos);
  // A dry run writes nothing.
  EXPECT_FALSE(std::filesystem::exists(out));
}

// Wedges: every combination gets a folder and a resolved scene (mesh paths made absolute), and
// a combination that is not a valid scene stops the command before anything is written.
TEST(FarmCommand, WedgesPlanEveryCombinationAndRefuseInvalidOnes) {
  const std::string out = (std::filesystem::temp_directory_path() / ("magbake_wedge_" + std::to_string(::getpid()))).string();
  const std::string bowl = scene("paper/bowl_spheres.yaml");
  const Outcome r = magbake("farm " + bowl + " -o " + out +
                            " --wedge magnetics.theta=0.3,0.5 --wedge materials.steel.chi=100,700,2e4 --dry-run");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("#SBATCH --array=0-5\n"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(out + "/wedges/000_magnetics.theta=0.3_materials.steel.chi=100'"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(out + "/wedges/005_magnetics.theta=0.5_materials.steel.chi=2e4/scene.yaml"), std::string::npos);
  EXPECT_NE(r.out.find("--dependency=afterany:<wedge job> " + out + "/farm/summary.sh"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(out));
  // Bad syntax, a path that leads nowhere, and a value the scene validation refuses: exit 2.
  for (const std::string bad : {"magnetics.theta", "magnetics..theta=1", "bodies.nobody.position=[0, 0, 1]",
                                "materials.steel.chi=abc", "magnetics.theta=0.3,[1"}) {
    const Outcome b = magbake("farm " + bowl + " -o " + out + " --wedge '" + bad + "' --dry-run", true);
    EXPECT_EQ(b.code, 2) << bad << "\n" << b.out;
  }
  EXPECT_NE(magbake("farm " + bowl + " --wedge materials.steel.chi=abc", true).out.find("wedge case 0"), std::string::npos);
  // The same wedges from a file, one per line, with comments and blank lines.
  const std::string file = temp_scene("wedges.txt", "# theta and chi\nmagnetics.theta=0.3,0.5\n\n  materials.steel.chi=100,700,2e4\n");
  const Outcome f = magbake("farm " + bowl + " -o " + out + " --wedge-file " + file + " --dry-run");
  ASSERT_EQ(f.code, 0) << f.out;
  EXPECT_EQ(f.out, r.out);
  EXPECT_EQ(magbake("farm " + bowl + " --wedge-file /nonexistent/wedges.txt").code, 2);
}

TEST(FarmCommand, BadOptionsExitTwoAndAMissingSbatchExitsOneWithTheReason) {
  EXPECT_EQ(magbake("farm " + scene("demo.yaml") + " --engine tractor").code, 2);
  EXPECT_EQ(magbake("farm " + scene("demo.yaml") + " --chunk 0").code, 2);
  EXPECT_EQ(magbake("farm " + scene("demo.yaml") + " --partition 'a b'").code, 2);
  EXPECT_EQ(magbake("farm " + scene("demo.yaml") + " --submit --dry-run").code, 2);
  EXPECT_EQ(magbake("farm " + scene("no_such_scene.yaml")).code, 2);
  // An absolute outputs.cache names the shot folder only when allowed (as for bake).
  const std::string abs = temp_scene("abs.yaml",
                                     "magbake: 1\nname: abs\nunits: {length: mm, angle: deg}\n"
                                     "time: {fps: 30, frames: [1, 3], dt: 0.001}\nmaterials:\n  m: {kind: none, density: 1000}\n"
                                     "bodies:\n  - {name: a, shape: {box: [1, 1, 1]}, material: m}\n"
                                     "outputs:\n  cache: /tmp/magbake_abs_shot/abs.h5\n");
  EXPECT_EQ(magbake("farm " + abs).code, 2);
  EXPECT_NE(magbake("farm " + abs + " --allow-absolute-outputs").out.find("#SBATCH --output=/tmp/magbake_abs_shot/farm/logs/bake-%j.log"),
            std::string::npos);
  const std::string out = (std::filesystem::temp_directory_path() / ("magbake_farm_nosb_" + std::to_string(::getpid()))).string();
  // A PATH without sbatch, for the child only (env(1)).
  const std::string cmd = "env PATH=/nonexistent " + std::string(MAGBAKE_EXE) + " farm " + scene("demo.yaml") + " -o " +
                          out + " --submit 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string text;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), p)) text += buf.data();
  const int st = pclose(p);
  EXPECT_EQ(WIFEXITED(st) ? WEXITSTATUS(st) : -1, 1) << text;
  EXPECT_NE(text.find("sbatch is not in PATH"), std::string::npos) << text;
  std::filesystem::remove_all(out);
}

// A shot whose cache is already complete is not baked again by accident: --submit exits 2 and
// writes nothing; with --force it goes on (here to the missing sbatch), and the job's bake line
// replaces the cache (--force) unless it resumes a partial one.
TEST(FarmCommand, SubmitRefusesToReplaceACompleteCacheWithoutForce) {
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() / ("magbake_farm_done_" + std::to_string(::getpid()));
  std::filesystem::create_directories(out);
  std::ofstream(out / "demo.h5") << "a complete cache stands here";
  auto run = [&](const std::string& extra) {
    const std::string cmd = "env PATH=/nonexistent " + std::string(MAGBAKE_EXE) + " farm " + scene("demo.yaml") + " -o " +
                            out.string() + " --submit " + extra + " 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string text;
    std::array<char, 4096> buf;
    while (std::fgets(buf.data(), buf.size(), p)) text += buf.data();
    const int st = pclose(p);
    return std::make_pair(WIFEXITED(st) ? WEXITSTATUS(st) : -1, text);
  };
  const auto [code, text] = run("");
  EXPECT_EQ(code, 2) << text;
  EXPECT_NE(text.find("complete cache(s) would be replaced, e.g. " + (out / "demo.h5").string()), std::string::npos) << text;
  EXPECT_FALSE(std::filesystem::exists(out / "farm")) << "nothing written";
  const auto [forced, forced_text] = run("--force");
  EXPECT_EQ(forced, 1) << forced_text;
  EXPECT_NE(forced_text.find("sbatch is not in PATH"), std::string::npos) << forced_text;
  const Outcome dry = magbake("farm " + scene("demo.yaml") + " -o " + out.string() + " --dry-run");
  EXPECT_NE(dry.out.find("resume=--force\n"), std::string::npos) << dry.out;
  std::filesystem::remove_all(out);
}

}  // namespace
}  // namespace magbake::testing
