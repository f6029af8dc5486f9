// A soft ball next to a ball magnet against the exact answer (tests/data/soft_sphere_series.json,
// made by scripts/make_soft_sphere_series.py): a permanent ball is one exact dipole cell in magbake
// (physics.md §4), and a linear sphere in a point dipole's field has a closed-form Legendre series
// for its force, so every error here is the soft ball's own discretization (issue 14, outcome 3:
// 3% at default and 1% at high, from contact to 20 mm, asserted below). Independent of the
// converged numerical references in soft_reference.json; refining the cells converges to it
// (1.0 / 0.7 / 0.5 / 0.4 mm cells at high, 1 mm gap: -0.67 / -0.36 / -0.26 / -0.20%). Each bound
// is at most the error measured on 2026-12-07 plus 0.3 percentage points, so that a change that
// loses accuracy fails here, and at most issue 14's targets (3% default, 1% high).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "scene/load.h"
#include "support/reference_text.h"
#include "support/scene_eval.h"

namespace magbake::testing {
namespace {

TEST(SoftSphereSeries, ForceOnASoftBallNextToABallMagnetAtEveryPreset) {
  std::ifstream in(source_dir() + "/tests/data/soft_sphere_series.json");
  ASSERT_TRUE(in.good());
  const nlohmann::json ref = nlohmann::json::parse(in);
  ASSERT_EQ(ref["cases"].size(), 8u);
  // Measured 2026-12-07 (chi 700; chi 2e4 within 0.1 points): gap 0.05 / 1 / 5 / 20 mm
  // draft -52.0 / -44.1 / -23.2 / -4.9%, default (8 cells across the soft ball) -2.48 / -2.06 /
  // -1.26 / -1.05%, default with 4 across (the paper scenes' resolution) -16.5 / -12.8 / -6.1 /
  // -1.7%, high (14 across) -0.80 / -0.70 / -0.45 / -0.15%.
  const std::map<std::string, std::map<std::string, double>> bound = {
      {"0.05mm", {{"draft", 0.523}, {"default", 0.0278}, {"default+soft4", 0.168}, {"high", 0.01}}},
      {"1mm", {{"draft", 0.444}, {"default", 0.0236}, {"default+soft4", 0.131}, {"high", 0.01}}},
      {"5mm", {{"draft", 0.235}, {"default", 0.0156}, {"default+soft4", 0.064}, {"high", 0.0075}}},
      {"20mm", {{"draft", 0.052}, {"default", 0.0135}, {"default+soft4", 0.0196}, {"high", 0.0045}}}};
  for (const auto& [gap, by] : bound) {
    EXPECT_LE(by.at("default"), 0.03) << gap;  // issue 14's targets
    EXPECT_LE(by.at("high"), 0.01) << gap;
  }
  for (const auto& c : ref["cases"]) {
    const std::string name = c["name"].get<std::string>();
    const std::string gap = name.substr(name.find("_gap") + 4);
    const double exact = c["reference"].get<double>();
    ASSERT_GT(exact, 0);
    for (const char* quality : {"draft", "default", "default+soft4", "high"}) {
      const bool coarse = std::string(quality) == "default+soft4";
      const std::string text = replace_all(replace_all(c["scene"].get<std::string>(), "QUALITY", coarse ? "default" : quality),
                                           "CELL", coarse ? ", soft_cells_across: 4" : "");
      const magnetics::Result r = evaluate_at_start(scene::load_scene_text(text, source_dir() + "/tests/data/soft.yaml"));
      EXPECT_TRUE(r.induction.converged) << name << " at " << quality;
      // The ball is pulled towards the magnet above it, and the magnet equally the other way.
      EXPECT_NEAR(r.force[1][2], -r.force[0][2], 1e-9 * std::abs(exact)) << name;
      const double err = r.force[0][2] / exact - 1.0;
      std::printf("%-20s %-17s %+.2f%%\n", name.c_str(), quality, 100 * err);
      EXPECT_LT(std::abs(err), bound.at(gap).at(quality)) << name << " at " << quality;
    }
  }
}

// Graded 1.6 mm cells at the default preset, 20 mm from the magnet: the body-level walk of the
// forces let the whole soft ball act as one dipole on the magnet (the cell walk would have opened
// it), 11.2% low; nodes holding soft bodies now open as the cell walk's soft nodes do (forces.cpp).
TEST(SoftSphereSeries, FarSoftBallIsNotOneDipoleInTheBodyWalk) {
  std::ifstream in(source_dir() + "/tests/data/soft_sphere_series.json");
  ASSERT_TRUE(in.good());
  const nlohmann::json ref = nlohmann::json::parse(in);
  for (const auto& c : ref["cases"]) {
    if (c["name"] != "chi700_gap20mm") continue;
    const std::string text = replace_all(replace_all(c["scene"].get<std::string>(), "QUALITY", "default"), "CELL",
                                         ", cell_size: 1.6, grading: 1");
    const magnetics::Result r = evaluate_at_start(scene::load_scene_text(text, source_dir() + "/tests/data/soft.yaml"));
    const double err = r.force[0][2] / c["reference"].get<double>() - 1.0;
    std::printf("graded 1.6 mm cells, 20 mm: %+.2f%%\n", 100 * err);
    EXPECT_LT(std::abs(err), 0.0137);  // measured -1.07%
    return;
  }
  FAIL() << "case chi700_gap20mm missing";
}

}  // namespace
}  // namespace magbake::testing
