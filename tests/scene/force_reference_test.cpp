// Forces and torques between uniformly magnetized bodies against independent references
// (tests/data/force_reference.json, made by scripts/make_force_reference.py: magpylib 6.1's exact
// fields integrated over the target's surface charge): a cube and a cylinder above an axial
// cylinder magnet, a ball beside its curved side, from 0.5 mm to 20 mm gap, at every preset,
// with and without the cylinder's exact surface. What is asserted is what docs/physics.md §12
// and the README claim.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "magnetics/system.h"
#include "scene/load.h"
#include "scene/scene_magnetics.h"
#include "support/reference_text.h"
#include "support/scene_eval.h"

namespace magbake::testing {
namespace {

using magnetics::Vec3;

Vec3 vec(const nlohmann::json& j) { return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>()); }

nlohmann::json reference() {
  std::ifstream in(source_dir() + "/tests/data/force_reference.json");
  EXPECT_TRUE(in.good());
  return nlohmann::json::parse(in);
}

// Relative errors of the force on the target (|F - F_ref| / |F_ref|) and of its torque about
// its centre (relative to |T_ref| + |F_ref| times the target's half size, 5 mm or 2 mm: the
// torque a force's error would give at the target's edge) at gap q of case c.
struct Errors {
  double force = 0, torque = 0;
  std::int64_t surface_pairs = 0;
};

Errors errors_at(const nlohmann::json& c, std::size_t q, const std::string& quality, bool surfaces) {
  const Vec3 center = vec(c["target_center"][q]) * 1e3;
  std::string text = replace_all(c["scene"].get<std::string>(), "QUALITY", quality);
  char buf[3][32];
  for (int k = 0; k < 3; ++k) std::snprintf(buf[k], sizeof buf[k], "%.9g", center[k]);
  text = replace_all(replace_all(replace_all(text, "TX", buf[0]), "TY", buf[1]), "TZ", buf[2]);
  scene::Scene sc = scene::load_scene_text(text, source_dir() + "/tests/data/ref.yaml");
  if (!surfaces) sc.magnetics.surface_tolerance = 0;
  const magnetics::Result r = evaluate_at_start(sc);
  const Vec3 F = r.force[1], T = r.torque[1];
  const Vec3 Fr = vec(c["force"][q]), Tr = vec(c["torque"][q]);
  const double half = c["name"] == "ball_beside_cylinder" ? 0.002 : 0.005;
  Errors e;
  e.force = (F - Fr).norm() / Fr.norm();
  e.torque = (T - Tr).norm() / (Tr.norm() + half * Fr.norm());
  e.surface_pairs = r.stats.surface_pairs;
  // Newton's third law and the angular momentum of the pair hold whatever the field's error.
  EXPECT_LT((r.force[0] + F).norm(), 1e-12 * F.norm());
  const Vec3 L = r.torque[0] + r.torque[1] + (center * 1e-3).cross(F);
  EXPECT_LT(L.norm(), 1e-12 * (T.norm() + 0.01 * F.norm()));
  return e;
}

TEST(ForceReference, MagnetsNearACurvedMagnetFeelItsExactSurfaceField) {
  // Asserted (force and torque, relative): from 0.5 to 5 mm, where the target opens the
  // cylinder's surface, per case at about 1.3-2x the error measured when this was written
  // (physics.md §12 quotes those); at 20 mm the tree's dipole aggregate of the cylinder's cells
  // takes over (its octupole-order shape error, as for the field). A ball is one exact cell, so
  // against the exact surface its force is the reference's to rounding; a cube's full cells are
  // point samples of the field (fourth order in cell size); a cylinder target keeps its cell
  // staircase, which now sets its error.
  const std::map<std::string, std::map<std::string, double>> bound = {
      {"cube_over_cylinder", {{"draft", 0.04}, {"default", 0.012}, {"high", 0.002}}},
      {"cylinder_over_cylinder", {{"draft", 0.025}, {"default", 0.03}, {"high", 0.008}}},
      {"ball_beside_cylinder", {{"draft", 3e-5}, {"default", 2e-6}, {"high", 2e-6}}},
      {"far", {{"draft", 0.04}, {"default", 0.04}, {"high", 0.004}}}};
  const nlohmann::json ref = reference();
  ASSERT_EQ(ref["cases"].size(), 3u);
  for (const auto& c : ref["cases"]) {
    const std::string name = c["name"];
    for (const std::string quality : {"draft", "default", "high"}) {
      for (const bool surfaces : {true, false}) {
        std::string line;
        for (std::size_t q = 0; q < c["gap"].size(); ++q) {
          const double gap = c["gap"][q].get<double>();
          const Errors e = errors_at(c, q, quality, surfaces);
          char buf[96];
          std::snprintf(buf, sizeof buf, "%4.1f mm: F %.1e T %.1e  ", gap * 1e3, e.force, e.torque);
          line += buf;
          if (!surfaces) {
            // The cells alone, 0.5 mm off at default: what the surfaces replaced.
            if (quality == "default" && q == 0) {
              EXPECT_GT(e.force, 0.03) << name;
            }
            continue;
          }
          const double tol = bound.at(gap <= 0.005 ? name : "far").at(quality);
          EXPECT_LT(e.force, tol) << name << " at " << quality << ", gap " << gap << " m";
          EXPECT_LT(e.torque, tol) << name << " at " << quality << ", gap " << gap << " m";
          if (gap <= 0.005) {
            EXPECT_GT(e.surface_pairs, 0) << name;
          }
        }
        std::printf("%-22s %-7s %-8s %s\n", name.c_str(), quality.c_str(), surfaces ? "surface" : "cells", line.c_str());
      }
    }
  }
}

}  // namespace
}  // namespace magbake::testing
