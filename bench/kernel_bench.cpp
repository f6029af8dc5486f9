// Throughput of the dipole-pair block kernels (force + torque + energy per pair), beside the
// machine's measured floating-point peak. One thread: numbers are per core.
#include <benchmark/benchmark.h>

#include <immintrin.h>

#include <random>

#include "magnetics/block_kernel.h"
#include "magnetics/cuboid.h"

namespace {

using namespace magbake::magnetics;

// A state holding two clouds of n cells each (1 mm lattice-ish spacing, random moments).
State make_state(int n) {
  State s;
  const int total = 2 * n;
  s.cell_offset.resize(total);
  s.total.cell.resize(total);
  for (auto* v : {&s.fx, &s.fy, &s.fz, &s.fmx, &s.fmy, &s.fmz, &s.fclamp}) v->resize(total);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.004, 0.004), mm(-1e-3, 1e-3);
  for (int c = 0; c < total; ++c) {
    s.cell_offset[c] = Vec3(u(rng), u(rng), u(rng));
    s.total.cell[c] = Vec3(mm(rng), mm(rng), mm(rng));
    s.fx[c] = float(s.cell_offset[c][0]), s.fy[c] = float(s.cell_offset[c][1]), s.fz[c] = float(s.cell_offset[c][2]);
    s.fmx[c] = float(s.total.cell[c][0]), s.fmy[c] = float(s.total.cell[c][1]), s.fmz[c] = float(s.total.cell[c][2]);
    s.fclamp[c] = 5e-4f;
  }
  return s;
}

void BM_Block(benchmark::State& state, KernelPrecision precision, bool clamp) {
  const int n = static_cast<int>(state.range(0));
  const State s = make_state(n);
  const Vec3 delta(0.02, 0.001, 0.003);  // second cloud 2 cm away
  BlockSum out;
  for (auto _ : state) {
    block_interaction(s, 0, n, n, 2 * n, delta, clamp, precision, out);
    benchmark::DoNotOptimize(out);
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(n) * n);
  state.counters["pairs/s"] = benchmark::Counter(double(state.iterations()) * n * n, benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_Block, f32, KernelPrecision::kSingle, false)->Arg(32)->Arg(64)->Arg(256);

// The exact near field of two touching 2.5 mm cells (the cells of two 1 cm cube magnets face to
// face at the default preset), force + torque + energy by cuboid_pair at quadrature order 4:
// parallel cells, and cells whose bodies have turned by `turn` rad about a skew axis (the
// magnetizations then carry round-off components along the other axes, which must not cost
// the four other faces: physics.md §6, bench/results/cuboid_near_2026-12-05).
void BM_CuboidPair(benchmark::State& state, double turn) {
  const Mat3 R = Eigen::AngleAxisd(turn, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  const Vec3 half(1.25e-3, 1.25e-3, 1.25e-3);
  const double M = 1.3 / 4e-7 / 3.141592653589793;  // N42, A/m
  const Cuboid k{R * Vec3(0.3e-3, 0.2e-3, 2.5e-3), R, half, R * Vec3(0, 0, M)};
  const Cuboid i{Vec3::Zero(), R, half, R * Vec3(0, 0, M)};
  Vec3 F, T;
  double E = 0;
  for (auto _ : state) {
    cuboid_pair(k, i, 4, F, T, &E);
    benchmark::DoNotOptimize(F);
    benchmark::DoNotOptimize(E);
  }
  state.counters["pairs/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_CuboidPair, aligned, 0.0);
BENCHMARK_CAPTURE(BM_CuboidPair, turned, 0.3);
BENCHMARK_CAPTURE(BM_Block, f32_clamped, KernelPrecision::kSingle, true)->Arg(32)->Arg(256);
BENCHMARK_CAPTURE(BM_Block, f64, KernelPrecision::kDouble, false)->Arg(32)->Arg(256);

// Machine peak: 10 independent chains of 256-bit FMAs (enough to cover FMA latency).
template <class V, class Fma>
void peak(benchmark::State& state, V init, V a, V b, Fma fma, int lanes) {
  V acc[10];
  for (auto& x : acc) x = init;
  for (auto _ : state) {
    for (int r = 0; r < 100; ++r) {
      for (auto& x : acc) x = fma(x, a, b);
    }
    for (auto& x : acc) benchmark::DoNotOptimize(x);
  }
  state.counters["flop/s"] = benchmark::Counter(double(state.iterations()) * 100 * 10 * lanes * 2, benchmark::Counter::kIsRate);
}
void BM_PeakFmaF32(benchmark::State& s) {
  peak(s, _mm256_set1_ps(1.0f), _mm256_set1_ps(0.9999f), _mm256_set1_ps(1e-7f),
       [](__m256 x, __m256 a, __m256 b) { return _mm256_fmadd_ps(x, a, b); }, 8);
}
void BM_PeakFmaF64(benchmark::State& s) {
  peak(s, _mm256_set1_pd(1.0), _mm256_set1_pd(0.9999), _mm256_set1_pd(1e-7),
       [](__m256d x, __m256d a, __m256d b) { return _mm256_fmadd_pd(x, a, b); }, 4);
}
BENCHMARK(BM_PeakFmaF32);
BENCHMARK(BM_PeakFmaF64);

}  // namespace

BENCHMARK_MAIN();
