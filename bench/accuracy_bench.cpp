// Run time against error (the cube pair of the paper's Fig. 6 against Akoun–Yonnet), and the
// paper's "Gain" of adaptivity for a body pair at several distances. Writes CSV files;
// bench/plot_accuracy.py turns them into the Pareto plot. Single thread: times are per core.
//
//   accuracy_bench [out_dir]     (default bench/results)
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "geometry/shapes.h"
#include "magnetics/system.h"
#include "support/closed_forms.h"

namespace {

using namespace magbake;
using magnetics::Settings;
using magnetics::Vec3;

struct Pair {
  geometry::BoxShape a, b;
  magnetics::Model model;
  magnetics::State state;
  Pair(const Vec3& size, double cell) : a(size), b(size) {
    magnetics::Material j1;
    j1.kind = magnetics::MaterialKind::kPermanent;
    j1.remanence = 1.0;
    std::vector<magnetics::BodySpec> bodies(2);
    bodies[0].parts.push_back({&a, {}, j1});
    bodies[1].parts.push_back({&b, {}, j1});
    magnetics::BuildSettings bs;
    bs.cell_size = cell;
    model = magnetics::build_model(bodies, bs);
    state.resize(model);
  }
};

// Median wall time (s) of evaluate() over enough repetitions to fill ~0.3 s (at least 3).
double median_time(Pair& p, const Settings& st, magnetics::Result& r) {
  std::vector<double> t;
  double total = 0;
  while (t.size() < 3 || (total < 0.3 && t.size() < 200)) {
    const auto t0 = std::chrono::steady_clock::now();
    magnetics::evaluate(p.model, st, p.state, r);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    t.push_back(dt);
    total += dt;
  }
  std::nth_element(t.begin(), t.begin() + t.size() / 2, t.end());
  return t[t.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path out = argc > 1 ? argv[1] : "bench/results";
  std::filesystem::create_directories(out);
  tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);

  // ---- 1. Cube pair: run time against error.
  FILE* f = std::fopen((out / "cube_pair_time_vs_error.csv").c_str(), "w");
  std::fprintf(f, "gap_mm,method,cell_mm,theta,near_field,cells,time_ms,force_N,exact_N,rel_error,cell_pairs,node_pairs,near_pairs\n");
  const Vec3 h(0.005, 0.005, 0.005);
  struct Method {
    const char* name;
    double theta, near;
    std::vector<int> n;  // cells per edge
  };
  const Method methods[] = {
      {"dipoles-uniform", 0.0, 0.0, {2, 4, 6, 8, 10, 12, 16}},       // the paper's method
      {"nearfield-uniform", 0.0, 2.5, {2, 4, 6, 8, 10, 12, 16}},     // + exact cuboid near field
      {"nearfield-theta0.3", 0.3, 2.5, {4, 8, 12, 16, 20}},
      {"nearfield-theta0.5", 0.5, 2.5, {4, 8, 12, 16, 20}},
      {"nearfield-theta0.7", 0.7, 2.5, {4, 8, 12, 16, 20}},
  };
  for (double gap_mm : {0.0, 1.0, 5.0, 20.0}) {
    const double exact = testing::akoun_yonnet_force(1, 1, h, h, Vec3(0, 0, 0.01 + gap_mm * 1e-3))[2];
    for (const Method& m : methods) {
      for (int n : m.n) {
        Pair p(Vec3(0.01, 0.01, 0.01), 0.01 / n);
        p.state.body_pose[1].position = Vec3(0, 0, 0.01 + gap_mm * 1e-3);
        Settings st;
        st.theta = m.theta;
        st.near_field = m.near;
        magnetics::Result r;
        const double t = median_time(p, st, r);
        const double err = std::abs(r.force[1][2] / exact - 1.0);
        std::fprintf(f, "%g,%s,%g,%g,%g,%d,%.6g,%.8g,%.8g,%.4e,%lld,%lld,%lld\n", gap_mm, m.name, 10.0 / n, m.theta,
                     m.near, p.model.cell_count(), t * 1e3, r.force[1][2], exact, err, (long long)r.stats.cell_pairs,
                     (long long)r.stats.node_pairs, (long long)r.stats.near_pairs);
        std::printf("gap %4.1f mm  %-20s N=%2d  %8.3f ms  error %.2e\n", gap_mm, m.name, n, t * 1e3, err);
        std::fflush(stdout);
      }
    }
  }
  std::fclose(f);

  // ---- 2. Gain of adaptivity (paper Table 1): two 2 cm cubes of 1 mm cells (8000 each).
  FILE* g = std::fopen((out / "gain.csv").c_str(), "w");
  std::fprintf(g, "distance_mm,theta,time_all_pairs_ms,time_adaptive_ms,gain,rel_force_error\n");
  Pair p(Vec3(0.02, 0.02, 0.02), 0.001);
  for (double d_mm : {21.0, 25.0, 30.0, 40.0, 60.0, 100.0, 200.0}) {
    p.state.body_pose[1].position = Vec3(0.003, 0.002, d_mm * 1e-3);
    Settings all;
    all.theta = 0.0;
    magnetics::Result r0, r1;
    const double t0 = median_time(p, all, r0);
    for (double theta : {0.3, 0.5}) {
      Settings ad = all;
      ad.theta = theta;
      const double t1 = median_time(p, ad, r1);
      const double err = (r1.force[1] - r0.force[1]).norm() / r0.force[1].norm();
      std::fprintf(g, "%g,%g,%.6g,%.6g,%.4g,%.3e\n", d_mm, theta, t0 * 1e3, t1 * 1e3, t0 / t1, err);
      std::printf("distance %5.0f mm theta %.1f: all pairs %8.2f ms, adaptive %7.3f ms, gain %6.1f, error %.1e\n",
                  d_mm, theta, t0 * 1e3, t1 * 1e3, t0 / t1, err);
      std::fflush(stdout);
    }
  }
  std::fclose(g);
  return 0;
}
