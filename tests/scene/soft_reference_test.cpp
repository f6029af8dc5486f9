// Soft (induced) bodies against converged references (tests/data/soft_reference.json, made by
// scripts/make_soft_reference.py: the coupled solve at 32,768-64,000 cells, extrapolated to zero
// cell size): a soft cube's moment in a uniform field and a soft sphere's force above a cube
// magnet, at draft, default and high, and at default with graded cells (`grading: 1`, the high
// preset's). Issue 14's targets (3% at default and 1% at high for chi up to 2e4) are not all met
// yet: each bound below is the error measured on 2026-12-06 (bench/results/soft_graded_2026-12-06)
// plus a margin of about 0.3 percentage points for the reference's own uncertainty, so that a
// change that loses accuracy fails here.
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
// `quality` is a preset, or "default+grading1" for the default preset with graded cells.
double value_at(const nlohmann::json& c, const std::string& quality) {
  const bool graded = quality == "default+grading1";
  const std::string text = replace_all(replace_all(c["scene"].get<std::string>(), "QUALITY", graded ? "default" : quality),
                                       "CELL", graded ? ", grading: 1" : "");
  const magnetics::Result r = evaluate_at_start(scene::load_scene_text(text, source_dir() + "/tests/data/soft.yaml"));
  EXPECT_TRUE(r.induction.converged) << c["name"] << " at " << quality;
  const int b = c["body"].get<int>();
  return c["quantity"] == "moment_z" ? r.moment[b][2] : r.force[b][2];
}

TEST(SoftReference, CubeMomentAndSphereForceAtEveryPreset) {
  // Measured (relative): cube chi 10 / 700 / 2e4: draft -8.4 / -13.8 / -13.9%, default -3.6 / -6.1 /
  // -6.2%, default graded -1.2 / -2.2 / -2.2%, high (graded) -0.41 / -0.57 / -0.57%; sphere 0.05 /
  // 1 / 5 / 20 mm above the magnet: draft +0.01 / -9.6 / -12.6 / -1.7%, default +10.9 / -2.6 / -3.2 /
  // -0.14%, default graded -1.6 / -2.0 / -0.88 / -1.6%, high (graded) -1.7 / -0.73 / -0.10 / +0.48%
  // (chi 700 and 2e4 within 0.05 points; the 20 mm case with kSoftSourceTheta in forces.cpp).
  const std::map<std::string, std::map<std::string, double>> bound = {
      {"cube_chi10", {{"draft", 0.087}, {"default", 0.039}, {"default+grading1", 0.015}, {"high", 0.0075}}},
      {"cube_chi700", {{"draft", 0.141}, {"default", 0.064}, {"default+grading1", 0.025}, {"high", 0.009}}},
      {"cube_chi20000", {{"draft", 0.142}, {"default", 0.065}, {"default+grading1", 0.025}, {"high", 0.009}}},
      // At contact the reference itself is uncertain by 2.9% (n = 20 and 24 differ by 0.7%,
      // converging from above), so the margin here is that, not 0.3 points.
      {"sphere_gap0.05mm", {{"draft", 0.03}, {"default", 0.14}, {"default+grading1", 0.045}, {"high", 0.046}}},
      {"sphere_gap1mm", {{"draft", 0.099}, {"default", 0.029}, {"default+grading1", 0.023}, {"high", 0.0105}}},
      {"sphere_gap5mm", {{"draft", 0.129}, {"default", 0.035}, {"default+grading1", 0.012}, {"high", 0.0045}}},
      {"sphere_gap20mm", {{"draft", 0.02}, {"default", 0.0045}, {"default+grading1", 0.019}, {"high", 0.008}}}};
  const nlohmann::json ref = reference();
  ASSERT_EQ(ref["cases"].size(), 11u);
  for (const auto& c : ref["cases"]) {
    std::string name = c["name"].get<std::string>();
    if (name.rfind("sphere", 0) == 0) name = "sphere" + name.substr(name.find("_gap"));
    const double r = c["reference"].get<double>();
    for (const char* quality : {"draft", "default", "default+grading1", "high"}) {
      const double err = value_at(c, quality) / r - 1.0;
      std::printf("%-24s %-8s %+.2f%%\n", c["name"].get<std::string>().c_str(), quality, 100 * err);
      EXPECT_LT(std::abs(err), bound.at(name).at(quality)) << c["name"] << " at " << quality;
    }
  }
}

}  // namespace
}  // namespace magbake::testing
