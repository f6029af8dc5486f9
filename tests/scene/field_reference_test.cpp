// B of uniformly magnetized bodies against independent references (tests/data/field_reference.json,
// made by scripts/make_field_reference.py with magpylib 6.1 and the ball's closed form): a cube, a
// cylinder magnetized along and across its axis, a ball and a mesh magnet (the horseshoe), from
// 0.5 mm off their surface to 20 cm, and inside them, at every quality preset. What is asserted
// is what docs/physics.md §12 and the README claim.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "magnetics/system.h"
#include "scene/load.h"
#include "scene/scene_magnetics.h"
#include "support/reference_text.h"

namespace magbake::testing {
namespace {

using magnetics::Vec3;

// Largest relative error |B - B_ref| / |B_ref| of one case at one preset, per distance band
// (-1 = inside), with the number of triangles its surfaces have.
struct CaseErrors {
  std::map<double, double> worst;
  int triangles = 0;
};

// `one_by_one`: each point alone (a target group of radius 0, as a probe of one point or a field
// line step sees it); otherwise all points in one call (groups of up to 32 spread over the case).
CaseErrors errors_of(const nlohmann::json& c, const std::string& quality, bool one_by_one = false) {
  std::string text = replace_all(c["scene"].get<std::string>(), "QUALITY", quality);
  text = replace_all(text, "MESH", source_dir() + "/scenes/meshes/horseshoe.obj");
  const scene::Scene sc = scene::load_scene_text(text, source_dir() + "/tests/data/ref.yaml");
  const magnetics::Model m = scene::build_magnetics_model(sc);
  magnetics::State st;
  st.resize(m);
  scene::set_poses_at(sc, 0.0, st);
  const magnetics::Settings settings = scene::magnetics_settings(sc);
  magnetics::Result r;
  magnetics::evaluate(m, settings, st, r);
  std::vector<Vec3> pts;
  for (const auto& p : c["points"]) pts.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  std::vector<Vec3> B = magnetics::field_at_points(m, settings, st, pts);
  if (one_by_one) {
    for (std::size_t q = 0; q < pts.size(); ++q) B[q] = magnetics::field_at_points(m, settings, st, {&pts[q], 1})[0];
  }
  CaseErrors e;
  e.triangles = m.surface_triangle_count();
  for (std::size_t q = 0; q < pts.size(); ++q) {
    const auto& b = c["B"][q];
    const Vec3 ref(b[0].get<double>(), b[1].get<double>(), b[2].get<double>());
    const double err = (B[q] - ref).norm() / ref.norm();
    double& w = e.worst[c["distance"][q].get<double>()];
    w = std::max(w, err);
  }
  return e;
}

nlohmann::json reference() {
  std::ifstream in(source_dir() + "/tests/data/field_reference.json");
  EXPECT_TRUE(in.good());
  return nlohmann::json::parse(in);
}

TEST(FieldReference, CurvedAndMeshMagnetsAreExactToTheirSurfaceAndInside) {
  // All of a case's points in one call: the target groups span the case, every group opens the
  // magnet, so this measures the surface field itself at every distance (a lone far point takes
  // the tree's dipoles instead: the next test). Claimed (physics.md §12): within 1% at default,
  // 0.1% at high, 3% at draft; asserted per case at about twice the error measured when this
  // was written (README and physics.md quote those), each within the claim.
  const std::map<std::string, double> claim = {{"draft", 0.03}, {"default", 0.01}, {"high", 0.001}};
  const std::map<std::string, std::map<std::string, double>> bound = {
      {"cube", {{"draft", 0.02}, {"default", 1e-3}, {"high", 1e-4}}},
      {"cylinder_tilted", {{"draft", 0.02}, {"default", 1e-3}, {"high", 2e-6}}},
      {"cylinder_axial", {{"draft", 1e-4}, {"default", 3e-6}, {"high", 1e-7}}},
      {"sphere", {{"draft", 2e-6}, {"default", 2e-6}, {"high", 2e-6}}},
      {"horseshoe", {{"draft", 2e-6}, {"default", 2e-6}, {"high", 2e-6}}}};
  const nlohmann::json ref = reference();
  ASSERT_EQ(ref["cases"].size(), 5u);
  for (const auto& c : ref["cases"]) {
    for (const auto& [quality, claimed] : claim) {
      const double tol = bound.at(c["name"].get<std::string>()).at(quality);
      ASSERT_LE(tol, claimed);
      const CaseErrors e = errors_of(c, quality);
      std::string line;
      for (const auto& [d, w] : e.worst) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%s: %.1e  ", d < 0 ? "inside" : (std::to_string(d * 1e3).substr(0, 5) + " mm").c_str(), w);
        line += buf;
        EXPECT_LT(w, tol) << c["name"] << " at " << quality << ", distance " << d << " m";
      }
      std::printf("%-16s %-8s %5d triangles  %s\n", c["name"].get<std::string>().c_str(), quality.c_str(), e.triangles,
                  line.c_str());
    }
  }
}

TEST(FieldReference, SinglePointsBeyondTheSurfaceRegionCarryTheTreesDipoleError) {
  // A point alone opens a part only within (r_p / theta) of its centre; beyond, the part's cells
  // (and farther the whole body) act as aggregated dipoles, whose error for a non-cubic magnet is
  // of order (r/d)^2 of its octupole-order shape term (physics.md §12, "Far from the surface").
  // Asserted: up to 2 mm off the surface (and inside) the claims above; farther, the measured
  // limit with a margin (worst measured: the horseshoe 35% at 20 mm at draft, 1.5% at 20 cm at
  // every preset, as one dipole; the cylinders 1.6-1.8% at 20 mm at default, 0.3-0.4% at high).
  const std::map<std::string, std::pair<double, double>> claim = {
      {"draft", {0.03, 0.5}}, {"default", {0.01, 0.03}}, {"high", {0.001, 0.03}}};
  const nlohmann::json ref = reference();
  for (const auto& c : ref["cases"]) {
    for (const auto& [quality, tol] : claim) {
      const CaseErrors e = errors_of(c, quality, true);
      std::string line;
      for (const auto& [d, w] : e.worst) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%s: %.1e  ", d < 0 ? "inside" : (std::to_string(d * 1e3).substr(0, 5) + " mm").c_str(), w);
        line += buf;
        EXPECT_LT(w, d <= 0.002 ? tol.first : tol.second) << c["name"] << " at " << quality << ", distance " << d << " m";
      }
      std::printf("one by one: %-16s %-8s %s\n", c["name"].get<std::string>().c_str(), quality.c_str(), line.c_str());
    }
  }
}

TEST(FieldReference, WithoutSurfacesTheCellsAreFarOffNearCurvedMagnets) {
  // The same cylinder from its cells alone (surface_tolerance 0): the error this replaced, so
  // the test above cannot pass by accident of the reference.
  const nlohmann::json ref = reference();
  const auto& c = ref["cases"][1];
  ASSERT_EQ(c["name"], "cylinder_tilted");
  std::string text = replace_all(c["scene"].get<std::string>(), "QUALITY", "default");
  const scene::Scene sc = scene::load_scene_text(text, source_dir() + "/tests/data/ref.yaml");
  scene::Scene cells_only = sc;
  cells_only.magnetics.surface_tolerance = 0;
  const magnetics::Model with = scene::build_magnetics_model(sc), without = scene::build_magnetics_model(cells_only);
  EXPECT_GT(with.surface_triangle_count(), 100);
  EXPECT_EQ(without.surface_triangle_count(), 0);
  magnetics::State st;
  st.resize(without);
  scene::set_poses_at(sc, 0.0, st);
  magnetics::Result r;
  magnetics::evaluate(without, scene::magnetics_settings(sc), st, r);
  std::vector<Vec3> pts;
  for (const auto& p : c["points"]) pts.emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  const std::vector<Vec3> B = magnetics::field_at_points(without, scene::magnetics_settings(sc), st, pts);
  double worst = 0;
  for (std::size_t q = 0; q < pts.size(); ++q) {
    if (c["distance"][q].get<double>() != 0.0005) continue;
    const auto& b = c["B"][q];
    const Vec3 refb(b[0].get<double>(), b[1].get<double>(), b[2].get<double>());
    worst = std::max(worst, (B[q] - refb).norm() / refb.norm());
  }
  std::printf("cylinder_tilted from its cells alone at default, 0.5 mm off: %.1f%%\n", 100 * worst);
  EXPECT_GT(worst, 0.05);
}

}  // namespace
}  // namespace magbake::testing
