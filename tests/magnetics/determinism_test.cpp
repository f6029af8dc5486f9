// Same inputs => bit-identical outputs, whatever the number of threads.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cstring>

#include "support/scenes.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

struct Snapshot {
  Result result;
  std::vector<Vec3> field;
};

Snapshot run(int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  Rig s;
  s.add(std::make_unique<geometry::TorusShape>(0.02, 0.005), permanent(1.3));
  for (int i = 0; i < 6; ++i) s.add(std::make_unique<geometry::SphereShape>(0.004), linear(i % 2 ? 700 : -1));
  s.add(std::make_unique<geometry::BoxShape>(Vec3(0.01, 0.01, 0.004)), permanent(1.0, Vec3(1, 0, 1)));
  s.build(0.0012, 16);
  for (int i = 0; i < 6; ++i) s.state.body_pose[1 + i].position = Vec3(0.02 * std::cos(i), 0.02 * std::sin(i), 0.009 + 0.001 * i);
  s.state.body_pose[7].position = Vec3(0.001, 0.002, 0.02);
  s.state.body_pose[7].rotation = Quat(Eigen::AngleAxisd(0.4, Vec3(1, 2, 0).normalized()));
  Settings st;
  st.external_field = Vec3(0, 1e-4, 5e-5);
  Snapshot snap;
  evaluate(s.model, st, s.state, snap.result);
  std::vector<Vec3> pts;
  for (int i = 0; i < 3000; ++i) pts.push_back(Vec3(0.0001 * i - 0.15, 0.00003 * i, 0.01));
  snap.field = field_at_points(s.model, st, s.state, pts);
  return snap;
}

bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0;
}

TEST(Determinism, OneAndTwoThreadsGiveIdenticalBits) {
  const Snapshot one = run(1), two = run(2), again = run(2);
  for (const Snapshot* s : {&two, &again}) {
    EXPECT_TRUE(same_bits(one.result.force, s->result.force));
    EXPECT_TRUE(same_bits(one.result.torque, s->result.torque));
    EXPECT_TRUE(same_bits(one.result.moment, s->result.moment));
    EXPECT_EQ(std::memcmp(&one.result.energy, &s->result.energy, sizeof(double)), 0);
    EXPECT_EQ(one.result.induction.iterations, s->result.induction.iterations);
    EXPECT_TRUE(same_bits(one.field, s->field));
  }
  EXPECT_GT(one.result.induction.iterations, 1);
}

TEST(Determinism, ResultsDoNotDependOnTheMachinesCacheSizes) {
  // Eigen sizes the blocks of its dense products (the induction preconditioner's LU) from the
  // CPU's cache sizes, which changes the summation order and so the rounding: the same binary
  // gave different caches on an Intel and an AMD machine. The model is built with fixed sizes.
  Eigen::setCpuCacheSizes(16 * 1024, 128 * 1024, 1024 * 1024);
  const Snapshot small = run(2);
  Eigen::setCpuCacheSizes(96 * 1024, 2048 * 1024, 384 * 1024 * 1024);
  const Snapshot large = run(2);
  EXPECT_TRUE(same_bits(small.result.force, large.result.force));
  EXPECT_TRUE(same_bits(small.result.moment, large.result.moment));
  EXPECT_EQ(std::memcmp(&small.result.energy, &large.result.energy, sizeof(double)), 0);
  EXPECT_TRUE(same_bits(small.field, large.field));
}

}  // namespace
}  // namespace magbake::testing
