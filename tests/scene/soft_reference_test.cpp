// Soft (induced) bodies against converged references (tests/data/soft_reference.json, made by
// scripts/make_soft_reference.py: the coupled solve at 32,768-64,000 cells, extrapolated to zero
// cell size): a soft cube's moment in a uniform field and a soft sphere's force above a cube
// magnet, at draft, default and high, and at default with `soft_cells_across: 4` (the paper
// scenes' resolution, and the default preset's before 2026-12-07). Issue 14's targets, 3% at
// default and 1% at high for chi up to 2e4, are asserted; every bound is also at most the error
// measured on 2026-12-07 (bench/results/soft_cells_2026-12-07) plus 0.3 percentage points, so
// that a change that loses accuracy fails here.
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

nlohmann::json reference() {
  std::ifstream in(source_dir() + "/tests/data/soft_reference.json");
  EXPECT_TRUE(in.good());
  return nlohmann::json::parse(in);
}

// The case's quantity (moment or force along z of its body) at a preset.
// `quality` is a preset, or "default+soft4" for the default preset with 4 cells across soft parts.
double value_at(const nlohmann::json& c, const std::string& quality) {
  const bool coarse = quality == "default+soft4";
  const std::string text = replace_all(replace_all(c["scene"].get<std::string>(), "QUALITY", coarse ? "default" : quality),
                                       "CELL", coarse ? ", soft_cells_across: 4" : "");
  const magnetics::Result r = evaluate_at_start(scene::load_scene_text(text, source_dir() + "/tests/data/soft.yaml"));
  EXPECT_TRUE(r.induction.converged) << c["name"] << " at " << quality;
  const int b = c["body"].get<int>();
  return c["quantity"] == "moment_z" ? r.moment[b][2] : r.force[b][2];
}

TEST(SoftReference, CubeMomentAndSphereForceAtEveryPreset) {
  // Measured 2026-12-07 (relative; chi 700 and 2e4 within 0.05 points): cube chi 10 / 700 / 2e4:
  // draft -8.4 / -13.8 / -13.9%, default -1.23 / -2.15 / -2.19%, default with 4 soft cells across
  // -3.6 / -6.1 / -6.2%, high -0.50 / -0.87 / -0.89%; sphere 0.05 / 1 / 5 / 20 mm above the
  // magnet: draft +0.01 / -9.6 / -12.6 / -1.7%, default -0.96 / -1.15 / -0.22 / -1.54%, default
  // with 4 across +10.9 / -2.6 / -3.2 / -0.14%, high -0.92 / -0.19 / +0.35 / +0.70%.
  const std::map<std::string, std::map<std::string, double>> bound = {
      {"cube_chi10", {{"draft", 0.087}, {"default", 0.0153}, {"default+soft4", 0.039}, {"high", 0.008}}},
      {"cube_chi700", {{"draft", 0.141}, {"default", 0.0245}, {"default+soft4", 0.064}, {"high", 0.01}}},
      {"cube_chi20000", {{"draft", 0.142}, {"default", 0.0249}, {"default+soft4", 0.065}, {"high", 0.01}}},
      // At contact the reference itself is uncertain by 2.9% (n = 20 and 24 differ by 0.7%,
      // converging from above), so the coarse columns' margin there is that, not 0.3 points.
      {"sphere_gap0.05mm", {{"draft", 0.03}, {"default", 0.0127}, {"default+soft4", 0.14}, {"high", 0.01}}},
      {"sphere_gap1mm", {{"draft", 0.099}, {"default", 0.0145}, {"default+soft4", 0.029}, {"high", 0.0049}}},
      {"sphere_gap5mm", {{"draft", 0.129}, {"default", 0.0055}, {"default+soft4", 0.035}, {"high", 0.0065}}},
      {"sphere_gap20mm", {{"draft", 0.02}, {"default", 0.0184}, {"default+soft4", 0.0045}, {"high", 0.01}}}};
  for (const auto& [name, by] : bound) {
    EXPECT_LE(by.at("default"), 0.03) << name;  // issue 14's targets
    EXPECT_LE(by.at("high"), 0.01) << name;
  }
  const nlohmann::json ref = reference();
  ASSERT_EQ(ref["cases"].size(), 11u);
  for (const auto& c : ref["cases"]) {
    std::string name = c["name"].get<std::string>();
    if (name.rfind("sphere", 0) == 0) name = "sphere" + name.substr(name.find("_gap"));
    const double r = c["reference"].get<double>();
    for (const char* quality : {"draft", "default", "default+soft4", "high"}) {
      const double err = value_at(c, quality) / r - 1.0;
      std::printf("%-24s %-8s %+.2f%%\n", c["name"].get<std::string>().c_str(), quality, 100 * err);
      EXPECT_LT(std::abs(err), bound.at(name).at(quality)) << c["name"] << " at " << quality;
    }
  }
}

}  // namespace
}  // namespace magbake::testing
