#include <cstdio>
#include <cstdlib>
#include <random>
#include <numbers>
#include "support/scenes.h"


using namespace magbake;
using namespace magbake::magnetics;
using namespace magbake::testing;
int main(int argc, char** argv) {
  const double cell = atof(argv[1]), theta = atof(argv[2]), B0 = atof(argv[3]);
  const int trials = atoi(argv[4]);
  const unsigned seed = argc > 5 ? atoi(argv[5]) : 7;
  Rig s;
  s.add(std::make_unique<geometry::SphereShape>(0.005), linear(700));
  s.add(std::make_unique<geometry::SphereShape>(0.005), linear(700));
  s.build(cell);
  Settings st;
  st.external_field = Vec3(0, 0, B0);
  st.theta = theta;
  st.induction_tolerance = 1e-6;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto random_turn = [&] {
    const Vec3 axis = Vec3(u(rng), u(rng), u(rng)).normalized();
    return Quat(Eigen::AngleAxisd(std::numbers::pi * u(rng), axis));
  };
  double fmin = 1e300, fmax = 0, mmax = 0;
  std::printf("cells %zu\n", s.model.induced_cells.size());
  for (int trial = 0; trial < trials; ++trial) {
    Vec3 dir = Vec3::UnitZ();
    double d = 0.01 - 5e-6;
    if (getenv("TURN")) {
    s.state.body_pose[0].rotation = random_turn();
    s.state.body_pose[1].rotation = random_turn();
    dir = Vec3(0.3 * u(rng), 0.3 * u(rng), 1.0).normalized();
    d = 0.0098502 + 0.00015 * u(rng);
    }
    s.state.body_pose[1].position = d * dir;
    Result r;
    evaluate(s.model, st, s.state, r);
    const double f = r.force[1].norm();
    double mm = 0;
    for (std::size_t k = 0; k < s.model.induced_cells.size(); ++k) {
      const int c = s.model.induced_cells[k];
      mm = std::max(mm, s.state.induced_moment[k].norm() / s.model.cell_volume[c]);
    }
    std::printf("trial %3d gap %+8.1f um  |F| %10.4g  maxM %9.3g  it %d res %.1e\n", trial, (d - 0.01) * 1e6, f, mm,
                r.induction.iterations, r.induction.residual);
    fmin = std::min(fmin, f); fmax = std::max(fmax, f); mmax = std::max(mmax, mm);
  }
  std::printf("|F| %.4g..%.4g N, largest M %.3g (lone sphere %.3g)\n", fmin, fmax, mmax, 3 * B0 / kMu0);
}
