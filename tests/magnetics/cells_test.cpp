// Cell decomposition and hierarchy invariants.
#include <gtest/gtest.h>

#include <numbers>

#include "support/scenes.h"

namespace magbake::testing {
namespace {

using namespace magnetics;

Vec3 total_moment(const Model& m, int body) {
  Vec3 s = Vec3::Zero();
  for (int c = m.body_cell_begin[body]; c < m.body_cell_begin[body + 1]; ++c) s += m.cell_moment[c];
  return s;
}

TEST(Cells, BoxGridFitsItsBoundsAndAllCellsAreFull) {
  Rig s;
  s.add(std::make_unique<geometry::BoxShape>(Vec3(0.01, 0.004, 0.007)), permanent(1.3));
  s.build(0.002);
  // ceil(10/2) x ceil(4/2) x ceil(7/2) = 5 x 2 x 4.
  EXPECT_EQ(s.model.cell_count(), 40);
  for (int c = 0; c < s.model.cell_count(); ++c) {
    EXPECT_TRUE(s.model.cell_full[c]);
    EXPECT_NEAR(s.model.cell_half[c][2], 0.007 / 8, 1e-15);
  }
  const Vec3 m = total_moment(s.model, 0);
  EXPECT_NEAR(m[2], 1.3 / kMu0 * 0.01 * 0.004 * 0.007, 1e-12 * m.norm());
}

TEST(Cells, CurvedShapesAreRescaledToTheirTrueVolume) {
  for (double cell : {0.004, 0.002, 0.001}) {
    Rig s;
    s.add(std::make_unique<geometry::SphereShape>(0.005), permanent(1.0));
    s.add(std::make_unique<geometry::CylinderShape>(0.003, 0.01), permanent(1.0, Vec3::UnitX()));
    s.add(std::make_unique<geometry::TorusShape>(0.006, 0.0015), permanent(1.0, Vec3::UnitY()));
    s.build(cell);
    const double V[3] = {4.0 / 3.0 * std::numbers::pi * 1.25e-7, std::numbers::pi * 9e-6 * 0.01,
                         2 * std::numbers::pi * std::numbers::pi * 0.006 * 1.5e-3 * 1.5e-3};
    const Vec3 dir[3] = {Vec3::UnitZ(), Vec3::UnitX(), Vec3::UnitY()};
    for (int b = 0; b < 3; ++b) {
      const Vec3 m = total_moment(s.model, b);
      EXPECT_LT((m - dir[b] / kMu0 * V[b]).norm(), 1e-12 * m.norm()) << "body " << b << " cell " << cell;
      // The measured (pre-rescale) volume is already close: inside fractions of boundary cells
      // (4 mm cells are coarser than the 3 mm torus tube: 15% there).
      const PartReport& rep = s.model.part_report[b];
      EXPECT_NEAR(rep.rescale, 1.0, cell > 0.003 ? 0.2 : 0.05) << "body " << b << " cell " << cell;
    }
  }
}

TEST(Cells, ThinTorusBelowTheCellSizeStillGetsCells) {
  Rig s;
  s.add(std::make_unique<geometry::TorusShape>(0.01, 0.0004), permanent(1.0));
  s.build(0.002);
  EXPECT_GE(s.model.cell_count(), 16);
  EXPECT_NEAR(total_moment(s.model, 0)[2], 1.0 / kMu0 * 2 * std::numbers::pi * std::numbers::pi * 0.01 * 1.6e-7,
              1e-9);
}

TEST(Cells, PartPoseMovesAndRotatesCells) {
  Rig s;
  Pose part;
  part.position = Vec3(0.01, 0, 0);
  part.rotation = Quat(Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitY()));  // z -> x
  s.add(std::make_unique<geometry::CylinderShape>(0.002, 0.006), permanent(1.0), part);
  s.build(0.001);
  const Vec3 m = total_moment(s.model, 0);
  EXPECT_NEAR(m.normalized()[0], 1.0, 1e-12);
  Vec3 c = Vec3::Zero();
  double v = 0;
  for (int q = 0; q < s.model.cell_count(); ++q) c += s.model.cell_volume[q] * s.model.cell_position[q], v += s.model.cell_volume[q];
  EXPECT_LT((c / v - part.position).norm(), 1e-6);
}

TEST(Cells, NonMagneticPartsAndBodiesGetNoCells) {
  Rig s;
  s.add(std::make_unique<geometry::BoxShape>(Vec3(0.01, 0.01, 0.01)), Material{});
  s.add(std::make_unique<geometry::SphereShape>(0.003), permanent(1.0));
  s.build(0.002);
  EXPECT_EQ(s.model.body_root[0], -1);
  EXPECT_EQ(s.model.body_cell_begin[1], 0);
  EXPECT_GT(s.model.cell_count(), 0);
}

TEST(Cells, TooManyCellsIsAnErrorNamingTheKnob) {
  Rig s;
  s.add(std::make_unique<geometry::BoxShape>(Vec3(1, 1, 1)), permanent(1.0));
  try {
    s.build(0.001);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("raise magnetics.cell_size"), std::string::npos) << e.what();
  }
}

TEST(Hierarchy, NodesAggregateAndBoundTheirCells) {
  Rig s;
  s.add(std::make_unique<geometry::TorusShape>(0.01, 0.004), permanent(1.0, Vec3(1, 1, 0)));
  Pose p;
  p.position = Vec3(0, 0, 0.003);
  s.bodies[0].parts.push_back({s.shapes[0].get(), p, linear(700)});
  s.build(0.001, 16);
  const Model& m = s.model;
  EXPECT_TRUE(m.body_permanent[0]);
  EXPECT_TRUE(m.body_induced[0]);
  for (int n = 0; n < m.node_count(); ++n) {
    Vec3 sum = Vec3::Zero();
    for (int c = m.node_begin[n]; c < m.node_end[n]; ++c) {
      sum += m.cell_moment[c];
      EXPECT_LE((m.cell_position[c] - m.node_center[n]).norm() + m.cell_reach[c], m.node_radius[n] * (1 + 1e-12));
    }
    EXPECT_LT((sum - m.node_moment[n]).norm(), 1e-9 * (sum.norm() + 1e-30));
    const int ch = m.node_child[n];
    if (ch < 0) {
      EXPECT_LE(m.node_end[n] - m.node_begin[n], 16);
    } else {
      // Children tile the parent's cell range in order.
      ASSERT_GE(m.node_nchild[n], 2);
      ASSERT_LE(m.node_nchild[n], 8);
      EXPECT_EQ(m.node_begin[ch], m.node_begin[n]);
      for (int k = ch; k + 1 < ch + m.node_nchild[n]; ++k) EXPECT_EQ(m.node_end[k], m.node_begin[k + 1]);
      EXPECT_EQ(m.node_end[ch + m.node_nchild[n] - 1], m.node_end[n]);
    }
  }
  EXPECT_EQ(m.induced_cells.size(), static_cast<std::size_t>(m.part_report[1].cells));
}

}  // namespace
}  // namespace magbake::testing
