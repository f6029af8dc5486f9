// Two soft balls in a uniform field along the line of their centres against the exact multipole
// series (tests/data/two_ball_series.json, made by scripts/make_two_ball_series.py): soft-soft
// contact, where both sides are cell staircases (issue 14). 5 mm balls, chi 100 and 700, 0.1 T,
// gaps 5 mm down to contact.
//
// What the series shows (physics.md §7, "Two soft balls: the exact pull"): under the linear law the
// pull of touching balls is finite but enormous (3.9 kN at chi 700, 164 N at chi 100) and comes from
// a ring of width ~a/chi around the contact where the law puts tens of tesla (8.9 T at the middle of
// a 0.05 mm gap): no cell size a scene can afford resolves it, and real steel saturates long
// before. So the gaps of 0.5 mm and more carry the accuracy bounds, and the smaller gaps only
// assert what holds at any resolution: the pull is attractive and below the exact one.
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

TEST(TwoBallSeries, PullOfTwoSoftBallsAtEveryPreset) {
  std::ifstream in(source_dir() + "/tests/data/two_ball_series.json");
  ASSERT_TRUE(in.good());
  const nlohmann::json ref = nlohmann::json::parse(in);
  ASSERT_EQ(ref["cases"].size(), 12u);
  // Relative error bounds: each at most the error measured on 2026-12-08 (bench/results/
  // two_balls_2026-12-08, chi 100 and 700 within 0.7 points of each other) plus 0.3 points.
  // Measured, chi 700: gap 5 / 2 / 0.5 mm: draft -9.0 / -27.3 / -63.2%, default -0.36 / -1.14 /
  // -5.81%, high -0.11 / -0.40 / -1.96%; chi 100 default -0.37 / -1.22 / -6.49% (high, not run
  // here, -2.75% at 0.5 mm). Before near induced bodies opened at 0.7 theta in the induction
  // (kOtherBodyTheta) default was -0.57 / -1.77 / -7.46% and high -0.12 / -0.50 / -2.28%. Issue
  // 14's 3% / 1% hold from 2 mm on, not at 0.5 mm. Below 0.5 mm the gap's field exceeds any
  // steel's saturation (1.3 T at 0.5 mm, 8.9 T at 0.05 mm): draft / default / high get 7-63% of
  // the linear law's pull at 0.05 mm and 0.05-9% at contact.
  const std::map<std::string, std::map<std::string, double>> bound = {
      {"5mm", {{"draft", 0.093}, {"default", 0.0067}, {"high", 0.0041}}},  // high not run here
      {"2mm", {{"draft", 0.277}, {"default", 0.0152}, {"high", 0.0070}}},
      {"0.5mm", {{"draft", 0.635}, {"default", 0.0679}, {"high", 0.0226}}}};
  for (const auto& [gap, by] : bound) {
    if (gap == "0.5mm") continue;
    EXPECT_LE(by.at("default"), 0.03) << gap;  // issue 14's targets
    EXPECT_LE(by.at("high"), 0.01) << gap;
  }
  int bounded = 0;
  for (const auto& c : ref["cases"]) {
    const std::string name = c["name"].get<std::string>();
    const std::string gap = name.substr(name.find("_gap") + 4);
    const double exact = c["reference"].get<double>();
    ASSERT_LT(exact, 0) << name;  // ball b at +x is pulled towards ball a
    const bool chi700 = c["chi"].get<double>() == 700.0;
    for (const char* quality : {"draft", "default", "high"}) {
      // high costs ~6 s a case (the factor of a 1,440-cell preconditioner block): chi 700 at 2 and
      // 0.5 mm only.
      if (std::string(quality) == "high" && (!chi700 || (gap != "2mm" && gap != "0.5mm"))) continue;
      const std::string text = replace_all(replace_all(c["scene"].get<std::string>(), "QUALITY", quality), "CELL", "");
      const magnetics::Result r = evaluate_at_start(scene::load_scene_text(text, source_dir() + "/tests/data/soft.yaml"));
      EXPECT_TRUE(r.induction.converged) << name << " at " << quality;
      EXPECT_NEAR(r.force[1][0], -r.force[0][0], 1e-9 * std::abs(exact)) << name;
      EXPECT_LT(std::abs(r.force[1][1]) + std::abs(r.force[1][2]), 1e-6 * std::abs(exact)) << name;
      const double err = r.force[1][0] / exact - 1.0;
      std::printf("%-18s %-8s %+.2f%%\n", name.c_str(), quality, 100 * err);
      if (bound.count(gap)) {
        EXPECT_LT(std::abs(err), bound.at(gap).at(quality)) << name << " at " << quality;
        ++bounded;
      } else {
        // Attractive, and short of the linear law's flux concentration at any resolution. The
        // lattice clamp of boundary cells (before 2026-12-07) broke this: 5371 N at contact at
        // 12 cells across (physics.md §7).
        EXPECT_LT(err, 0.0) << name << " at " << quality;
        EXPECT_GT(err, -1.0) << name << " at " << quality;
      }
    }
  }
  EXPECT_EQ(bounded, 3 * 2 * 2 + 2);  // draft and default at both chis, high at chi 700
}

}  // namespace
}  // namespace magbake::testing
