// The paper's scenes (scenes/paper): every one passes `magbake check`, and a short bake of each
// finishes with finite values and bodies where the shot puts them (nothing below the ground,
// nothing thrown far away). One test per scene so ctest runs them in parallel.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "io/cache.h"
#include "scene/load.h"
#include "support/shell.h"

namespace magbake::testing {
namespace {
namespace fs = std::filesystem;

std::string exe() { return MAGBAKE_EXE; }
fs::path paper_dir() { return fs::path(MAGBAKE_SOURCE_DIR) / "scenes" / "paper"; }

/// Every scene file in scenes/paper, sorted.
std::vector<std::string> paper_scenes() {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(paper_dir())) {
    if (e.path().extension() == ".yaml") out.push_back(e.path().stem().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(PaperScenes, AllTheIssueNamesArePresent) {
  const std::vector<std::string> have = paper_scenes();
  for (const char* name : {"tst", "bowl_spheres", "bowl_2008", "supercube", "dragon_low", "dragon_high", "field_lines"}) {
    EXPECT_NE(std::find(have.begin(), have.end(), name), have.end()) << name << ".yaml is missing";
  }
}

class PaperScene : public ::testing::TestWithParam<std::string> {};

TEST_P(PaperScene, ChecksAndAShortBakeStaysFiniteAndInPlace) {
  const std::string name = GetParam();
  const std::string scene = (paper_dir() / (name + ".yaml")).string();
  const Outcome check = sh(exe() + " check " + scene);
  ASSERT_EQ(check.code, 0) << check.out;
  EXPECT_NE(check.out.find("ok"), std::string::npos) << check.out;

  // Two frames (one frame interval of dynamics) keeps the whole set inside the CI budget; the
  // first frame of every shot already has its bodies in or near contact with something.
  const fs::path dir = fresh_temp_dir("magbake_paper_" + name);
  const Outcome bake = sh(exe() + " --quiet bake " + scene + " --frames 1-2 -o " + dir.string());
  ASSERT_EQ(bake.code, 0) << bake.out;
  fs::path cache;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() == ".h5") cache = e.path();
  }
  ASSERT_FALSE(cache.empty()) << "no cache in " << dir;

  const scene::Scene sc = scene::load_scene(scene);
  const io::CacheReader r(cache.string());
  ASSERT_EQ(r.frame_count(), 2);
  ASSERT_EQ(r.status(), io::BakeStatus::kComplete);
  for (int k = 0; k < r.frame_count(); ++k) {
    const io::CacheFrame f = r.frame(k);
    for (std::size_t b = 0; b < f.position.size(); ++b) {
      const std::string what = name + " frame " + std::to_string(f.frame) + " body " + sc.bodies[b].name;
      ASSERT_TRUE(f.position[b].allFinite() && f.orientation[b].coeffs().allFinite()) << what;
      ASSERT_TRUE(f.velocity[b].allFinite() && f.angular_velocity[b].allFinite()) << what;
      ASSERT_TRUE(f.force[b].allFinite() && f.torque[b].allFinite()) << what;
      // In one frame nothing moves further than free fall plus 1 m/s would take it.
      const double moved = (f.position[b] - sc.bodies[b].pose.position).norm();
      const double t = f.time;
      EXPECT_LT(moved, 0.5 * 9.81 * t * t + 1.0 * t + 1e-6) << what;
      EXPECT_LT(f.velocity[b].norm(), 9.81 * t + 1.0) << what;
    }
    for (const auto& m : f.induced_moment) ASSERT_TRUE(m.allFinite()) << name;
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Paper, PaperScene, ::testing::ValuesIn(paper_scenes()),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

}  // namespace
}  // namespace magbake::testing
