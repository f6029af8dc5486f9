// What a valid scene becomes: units, presets, poses, masses, meshes.
#include <gtest/gtest.h>

#include <numbers>

#include "magnetics/system.h"
#include "scene/load.h"
#include "scene/scene_magnetics.h"

namespace magbake::scene {
namespace {

std::string source_dir() { return MAGBAKE_SOURCE_DIR; }

TEST(Scene, UnitsAreConvertedToSI) {
  const Scene s = load_scene_text(
      "magbake: 1\nunits: {length: cm, angle: deg}\ngravity: [0, 0, -981]\n"
      "materials: {m: {kind: soft, chi: 10, density: 1000}}\n"
      "bodies:\n  - {name: a, shape: {box: [1, 2, 4]}, material: m, position: [1, 2, 3],"
      " orientation: {axis: [0, 0, 1], angle: 90}, velocity: [10, 0, 0]}\n",
      "x.yaml");
  const Body& b = s.bodies[0];
  EXPECT_NEAR(s.gravity[2], -9.81, 1e-12);
  EXPECT_TRUE(b.shape.size.isApprox(Vec3(0.01, 0.02, 0.04)));
  EXPECT_TRUE(b.pose.position.isApprox(Vec3(0.01, 0.02, 0.03)));
  EXPECT_NEAR(b.pose.rotation.angularDistance(Quat(Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitZ()))), 0, 1e-12);
  EXPECT_NEAR(b.mass, 1000 * 8e-6, 1e-15);
  EXPECT_NEAR(b.velocity[0], 0.1, 1e-15);
}

TEST(Scene, PresetsSetCellSizeThetaAndNearField) {
  auto load = [](const std::string& q) {
    return load_scene_text("magbake: 1\nunits: {length: mm, angle: deg}\nmagnetics: {quality: " + q + "}\n", "x.yaml");
  };
  EXPECT_EQ(load("draft").magnetics.cells_per_extent, 2);
  EXPECT_EQ(load("default").magnetics.cells_per_extent, 4);
  EXPECT_EQ(load("high").magnetics.cells_per_extent, 8);
  EXPECT_DOUBLE_EQ(load("high").magnetics.theta, 0.3);
  EXPECT_DOUBLE_EQ(load("draft").magnetics.theta, 0.7);
  EXPECT_DOUBLE_EQ(load("draft").magnetics.induction_tolerance, 1e-3);
  EXPECT_DOUBLE_EQ(load("default").magnetics.induction_tolerance, 1e-4);
  EXPECT_DOUBLE_EQ(load("high").magnetics.induction_tolerance, 1e-6);
  const Scene explicit_cell = load_scene_text(
      "magbake: 1\nunits: {length: mm, angle: deg}\n"
      "magnetics: {quality: high, cell_size: 2, theta: 0.4, induction_tolerance: 1.0e-8}\n",
      "x.yaml");
  EXPECT_DOUBLE_EQ(*explicit_cell.magnetics.cell_size, 0.002);
  EXPECT_DOUBLE_EQ(explicit_cell.magnetics.theta, 0.4);
  EXPECT_DOUBLE_EQ(magnetics_settings(explicit_cell).induction_tolerance, 1e-8);
}

TEST(Scene, KinematicKeysInterpolateAndHold) {
  const Scene s = load_scene_text(
      "magbake: 1\nunits: {length: m, angle: deg}\nmaterials: {m: {kind: none}}\n"
      "bodies:\n  - name: k\n    shape: {sphere: {radius: 0.01}}\n    material: m\n    motion: kinematic\n"
      "    keys:\n      - {t: 1, position: [0, 0, 1], orientation: {axis: [0, 0, 1], angle: 0}}\n"
      "      - {t: 3, position: [0, 0, 3], orientation: {axis: [0, 0, 1], angle: 90}}\n",
      "x.yaml");
  const Body& b = s.bodies[0];
  EXPECT_TRUE(b.pose_at(0).position.isApprox(Vec3(0, 0, 1)));
  EXPECT_TRUE(b.pose_at(2).position.isApprox(Vec3(0, 0, 2)));
  EXPECT_TRUE(b.pose_at(5).position.isApprox(Vec3(0, 0, 3)));
  EXPECT_NEAR(b.pose_at(2).rotation.angularDistance(Quat(Eigen::AngleAxisd(std::numbers::pi / 4, Vec3::UnitZ()))), 0,
              1e-12);
}

TEST(Scene, EveryMeshFormatGivesTheSameSolid) {
  double volume = 0;
  for (const char* ext : {"obj", "stl", "ply", "gltf"}) {
    const Scene s = load_scene_text(
        std::string("magbake: 1\nunits: {length: mm, angle: deg}\nmaterials: {m: {kind: soft, chi: 700, density: 7850}}\n"
                    "bodies:\n  - {name: h, shape: {mesh: {file: meshes/horseshoe.") +
            ext + "}}, material: m}\n",
        source_dir() + "/scenes/demo_inline.yaml");
    const double v = s.bodies[0].shape.shape->volume();
    EXPECT_NEAR(v, 6211.0866e-9, 1e-12) << ext;  // make_meshes.py prints the volume
    if (volume == 0) volume = v;
    EXPECT_NEAR(v, volume, 1e-7 * volume) << ext;  // glTF stores float32
  }
}

TEST(Scene, CellsLiveInTheCentreOfMassFrame) {
  // A mesh whose origin is far from its centroid: the model's cells are centred on the centroid.
  const Scene s = load_scene_text(
      "magbake: 1\nunits: {length: mm, angle: deg}\nmaterials: {m: {kind: soft, chi: 700, density: 7850}}\n"
      "bodies:\n  - {name: h, shape: {mesh: {file: meshes/horseshoe.obj}}, material: m}\n",
      source_dir() + "/scenes/x.yaml");
  const magnetics::Model m = build_magnetics_model(s);
  Vec3 c = Vec3::Zero();
  double v = 0;
  for (int i = 0; i < m.cell_count(); ++i) c += m.cell_volume[i] * m.cell_position[i], v += m.cell_volume[i];
  EXPECT_LT((c / v).norm(), 2e-4);  // 0.2 mm: boundary-cell centroids
  EXPECT_GT(s.bodies[0].com.norm(), 1e-3);
}

// Cells across each part's smallest extent: 4 for magnets and weak materials, 8 for soft parts
// at the default preset (14 at high, 2 at draft), `soft_cells_across` for soft parts alone, and
// `cell_size` over both. Cubes, so the counts are n^3.
TEST(Scene, SoftPartsGetTheirOwnCellsAcross) {
  auto cells = [](const std::string& magnetics) {
    const Scene s = load_scene_text(
        "magbake: 1\nunits: {length: mm, angle: deg}\nmagnetics: {" + magnetics + "}\n"
        "materials: {N42: {kind: permanent, remanence: 1.3, density: 7500}, steel: {kind: soft, chi: 700, density: 7850},"
        " alu: {kind: linear, chi: 2.2e-5, density: 2700}, ybco: {kind: superconductor, density: 6300}}\n"
        "bodies:\n"
        "  - {name: magnet, shape: {box: [10, 10, 10]}, material: N42, magnetization: [0, 0, 1]}\n"
        "  - {name: steel, shape: {box: [10, 10, 10]}, material: steel, position: [30, 0, 0]}\n"
        "  - {name: alu, shape: {box: [10, 10, 10]}, material: alu, position: [60, 0, 0]}\n"
        "  - {name: ybco, shape: {box: [10, 10, 10]}, material: ybco, position: [90, 0, 0]}\n",
        source_dir() + "/scenes/x.yaml");
    const magnetics::Model m = build_magnetics_model(s);
    std::vector<int> n;
    for (int b = 0; b < 4; ++b) n.push_back(m.body_cell_begin[b + 1] - m.body_cell_begin[b]);
    return n;
  };
  EXPECT_EQ(cells("quality: default"), (std::vector<int>{64, 512, 64, 64}));
  EXPECT_EQ(cells("quality: draft"), (std::vector<int>{8, 8, 8, 8}));
  EXPECT_EQ(cells("quality: high"), (std::vector<int>{512, 2744, 512, 512}));
  EXPECT_EQ(cells("quality: default, soft_cells_across: 4"), (std::vector<int>{64, 64, 64, 64}));
  EXPECT_EQ(cells("soft_cells_across: 5, quality: default"), (std::vector<int>{64, 125, 64, 64}));  // key order is free
  EXPECT_EQ(cells("cell_size: 5, soft_cells_across: 6"), (std::vector<int>{8, 8, 8, 8}));
}

TEST(Scene, SoftSpheresFeelNoMagneticTorque) {
  // A soft sphere's energy does not change as it turns, so its exact torque is zero; the cell
  // model's staircase (one cube at this cell size) gives a spurious one, which spun the balls of
  // the paper's dragon scenes up to 1e5 rad/s. A soft cube at the same place keeps its torque.
  const Scene s = load_scene_text(
      "magbake: 1\nunits: {length: mm, angle: deg}\n"
      "materials: {N42: {kind: permanent, remanence: 1.3, density: 7500}, steel: {kind: soft, chi: 700, density: 7850}}\n"
      "magnetics: {quality: default, cell_size: 4}\n"
      "bodies:\n"
      "  - {name: magnet, shape: {box: [10, 10, 10]}, material: N42, magnetization: [1, 1, 0]}\n"
      "  - {name: ball, shape: {sphere: {radius: 2}}, material: steel, position: [8, 3, 2], orientation: {axis: [1, 2, 3], angle: 40}}\n"
      "  - {name: cube, shape: {box: [4, 4, 4]}, material: steel, position: [-8, 3, -2], orientation: {axis: [1, 2, 3], angle: 40}}\n",
      source_dir() + "/scenes/x.yaml");
  const magnetics::Model m = build_magnetics_model(s);
  magnetics::State st;
  st.resize(m);
  set_poses_at(s, 0.0, st);
  magnetics::Result r;
  magnetics::evaluate(m, magnetics_settings(s), st, r);
  EXPECT_GT(r.force[1].norm(), 1e-2);
  EXPECT_EQ(r.torque[1], Vec3::Zero());
  EXPECT_GT(r.torque[2].norm(), 1e-3 * r.force[2].norm() * 2e-3);  // the cube's shape torque
  EXPECT_GT(r.torque[0].norm(), 0.0);
}

TEST(Scene, IdenticalShapesShareOneGeometryObject) {
  // Derived data (convex pieces, demagnetization tensors) is cached per geometry object, so a
  // heap of identical bodies must share it; different sizes must not.
  const Scene s = load_scene_text(
      "magbake: 1\nunits: {length: mm, angle: deg}\nmaterials: {m: {kind: soft, chi: 700, density: 7850}}\n"
      "bodies:\n"
      "  - {name: a, shape: {mesh: {file: meshes/horseshoe.obj}}, material: m}\n"
      "  - {name: b, shape: {mesh: {file: meshes/horseshoe.obj}}, material: m, position: [50, 0, 0]}\n"
      "  - {name: c, shape: {mesh: {file: meshes/horseshoe.obj, scale: 2}}, material: m, position: [0, 50, 0]}\n"
      "  - {name: d, shape: {torus: {major: 6, minor: 2}}, material: m, position: [0, 0, 50]}\n"
      "  - {name: e, shape: {torus: {major: 6, minor: 2}}, material: m, position: [0, 0, 80]}\n"
      "  - {name: f, shape: {torus: {major: 6, minor: 3}}, material: m, position: [0, 0, 110]}\n",
      source_dir() + "/scenes/x.yaml");
  EXPECT_EQ(s.bodies[0].shape.shape.get(), s.bodies[1].shape.shape.get());
  EXPECT_NE(s.bodies[0].shape.shape.get(), s.bodies[2].shape.shape.get());
  EXPECT_NEAR(s.bodies[2].mass, 8 * s.bodies[0].mass, 1e-9 * s.bodies[2].mass);
  EXPECT_EQ(s.bodies[3].shape.shape.get(), s.bodies[4].shape.shape.get());
  EXPECT_NE(s.bodies[3].shape.shape.get(), s.bodies[5].shape.shape.get());
}

}  // namespace
}  // namespace magbake::scene

namespace magbake::scene {
namespace {

// The format 1.1 example shots (scenes/format11: a compass on a pivot, a damped pendulum, a
// rotating field) load, with the joints, damping and fields they describe.
TEST(Scene, TheFormat11ExampleShotsLoad) {
  const Scene compass = load_scene(source_dir() + "/scenes/format11/compass.yaml");
  ASSERT_EQ(compass.joints.size(), 1u);
  EXPECT_EQ(compass.joints[0].type, JointType::kHinge);
  EXPECT_EQ(compass.bodies[compass.joints[0].a].name, "needle");
  EXPECT_GT(compass.bodies[compass.joints[0].a].angular_damping, 0);
  const Scene pendulum = load_scene(source_dir() + "/scenes/format11/pendulum.yaml");
  ASSERT_EQ(pendulum.joints.size(), 1u);
  EXPECT_GT(pendulum.bodies[pendulum.body_index("bob")].linear_damping, 0);
  const Scene rotating = load_scene(source_dir() + "/scenes/format11/rotating_field.yaml");
  EXPECT_TRUE(rotating.applied_field_animated());
  EXPECT_LT((rotating.applied_field(0.25) - Vec3(0, 0.002, 0)).norm(), 1e-15);
}

}  // namespace
}  // namespace magbake::scene
