// magbake: command-line baker for magnetic rigid-body shots.
#include <CLI/CLI.hpp>

#include <cstdio>

#include "geometry/shapes.h"
#include "magnetics/system.h"

namespace {

using namespace magbake;

// Library demo until `magbake bake` exists: the paper's cube pair (Fig. 6).
int run_cubes(double gap_mm, double cell_mm, double theta) {
  geometry::BoxShape cube(magnetics::Vec3(0.01, 0.01, 0.01));
  magnetics::Material n42;
  n42.kind = magnetics::MaterialKind::kPermanent;
  n42.remanence = 1.0;
  std::vector<magnetics::BodySpec> bodies(2);
  for (auto& b : bodies) b.parts.push_back({&cube, {}, n42});
  magnetics::BuildSettings bs;
  bs.cell_size = cell_mm * 1e-3;
  const magnetics::Model model = magnetics::build_model(bodies, bs);
  magnetics::State state;
  state.resize(model);
  state.body_pose[1].position = magnetics::Vec3(0, 0, 0.01 + gap_mm * 1e-3);
  magnetics::Settings st;
  st.theta = theta;
  magnetics::Result r;
  magnetics::evaluate(model, st, state, r);
  std::printf("two 1 cm cubes, J = 1 T, gap %.3g mm, %d cells, theta %.2f\n", gap_mm, model.cell_count(), theta);
  std::printf("force on upper cube: %.5f %.5f %.5f N\n", r.force[1][0], r.force[1][1], r.force[1][2]);
  std::printf("pairs: %lld node, %lld cell, %lld near-field\n", (long long)r.stats.node_pairs,
              (long long)r.stats.cell_pairs, (long long)r.stats.near_pairs);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"magbake - baker for magnetic rigid-body shots"};
  app.require_subcommand(1);
  double gap = 5, cell = 2.5, theta = 0.5;
  auto* cubes = app.add_subcommand("cubes", "library demo: force between the paper's two 1 cm cube magnets");
  cubes->add_option("--gap", gap, "face gap, mm")->capture_default_str();
  cubes->add_option("--cell", cell, "cell size, mm")->capture_default_str();
  cubes->add_option("--theta", theta, "opening angle")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (*cubes) return run_cubes(gap, cell, theta);
  return 2;
}
