// Every kind of bad input is an error at the right file:line:col with a useful message.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "scene/load.h"
#include "support/shell.h"

namespace magbake::scene {
namespace {

// Loads scene text; returns the diagnostics (empty if it loaded).
Diagnostics problems(const std::string& text, const std::string& file = "test.yaml") {
  try {
    load_scene_text(text, file);
    return Diagnostics(file);
  } catch (const SceneError& e) {
    return e.diagnostics();
  }
}

// True if some diagnostic is at (line, col) and contains `needle`; prints all otherwise.
::testing::AssertionResult has(const Diagnostics& d, int line, int col, const std::string& needle) {
  for (const auto& x : d.items()) {
    if (x.loc.line == line && x.loc.col == col && (x.message + " " + x.path).find(needle) != std::string::npos) {
      return ::testing::AssertionSuccess();
    }
  }
  return ::testing::AssertionFailure() << "no diagnostic at " << line << ":" << col << " containing '" << needle
                                       << "'; got:\n"
                                       << d.format();
}

const std::string kHead = "magbake: 1\nunits: {length: mm, angle: deg}\n";
const std::string kMat = "materials:\n  N42: {kind: permanent, remanence: 1.3, density: 7500}\n  steel: {kind: soft, chi: 700, density: 7850}\n";

TEST(SceneValidation, AValidSceneLoads) {
  const Diagnostics d = problems(kHead + kMat +
                                 "bodies:\n"
                                 "  - {name: a, shape: {sphere: {radius: 2}}, material: steel}\n");
  EXPECT_TRUE(d.empty()) << d.format();
}

TEST(SceneValidation, UnknownKeyWithSuggestion) {
  const Diagnostics d = problems(kHead + kMat +
                                 "bodies:\n"
                                 "  - name: a\n"
                                 "    shape: {sphere: {radius: 2}}\n"
                                 "    material: steel\n"
                                 "    restitutoin: 0.3\n");
  EXPECT_TRUE(has(d, 10, 5, "unknown key 'restitutoin' (did you mean 'restitution'?)"));
  EXPECT_NE(d.format().find("test.yaml:10:5: bodies[0].restitutoin: unknown key"), std::string::npos) << d.format();
}

// outputs.usd: a .usda, .usdc or .usd path inside the output folder; anything else at its file:line:col.
TEST(SceneValidation, OutputsUsdIsAUsdaPathInsideTheOutputFolder) {
  const std::string body = "bodies:\n  - {name: a, shape: {sphere: {radius: 2}}, material: steel}\n";
  EXPECT_TRUE(problems(kHead + kMat + body + "outputs:\n  usd: out/shot.usda\n").empty());
  EXPECT_TRUE(problems(kHead + kMat + body + "outputs:\n  usd: out/shot.usdc\n").empty());
  EXPECT_TRUE(problems(kHead + kMat + body + "outputs:\n  usd: out/shot.usd\n").empty());
  EXPECT_TRUE(has(problems(kHead + kMat + body + "outputs:\n  usd: out/shot.usdz\n"), 9, 8, "expected a .usda (text), .usdc or .usd"));
  EXPECT_TRUE(has(problems(kHead + kMat + body + "outputs:\n  usd: ../shot.usda\n"), 9, 8, "outputs.usd"));
  EXPECT_TRUE(has(problems(kHead + kMat + body + "outputs:\n  usd: [1, 2]\n"), 9, 8, "outputs.usd"));
}

TEST(SceneValidation, UnknownTopLevelKey) {
  EXPECT_TRUE(has(problems(kHead + "gravitty: [0, 0, -9.81]\n"), 3, 1, "did you mean 'gravity'"));
}

TEST(SceneValidation, MissingRequiredKeyIsReportedAtItsParent) {
  EXPECT_TRUE(has(problems("magbake: 1\nname: x\n"), 1, 1, "missing required key 'units'"));
  const Diagnostics d = problems(kHead + kMat + "bodies:\n  - {name: a, material: steel}\n");
  EXPECT_TRUE(has(d, 7, 5, "missing required key 'shape'"));
}

TEST(SceneValidation, WrongType) {
  EXPECT_TRUE(has(problems(kHead + "magnetics: {theta: fast}\n"), 3, 20, "expected a number, got 'fast'"));
  EXPECT_TRUE(has(problems(kHead + "gravity: [0, 0]\n"), 3, 10, "expected a list of 3 numbers, got 2"));
  EXPECT_TRUE(has(problems(kHead + "bodies: {a: 1}\n"), 3, 9, "expected a list of bodies"));
}

TEST(SceneValidation, NegativeOrZeroSizes) {
  const Diagnostics d = problems(kHead + kMat +
                                 "bodies:\n"
                                 "  - {name: a, shape: {box: [1, -2, 3]}, material: steel}\n"
                                 "  - {name: b, shape: {sphere: {radius: 0}}, material: steel}\n"
                                 "  - {name: c, shape: {cylinder: {radius: 1, height: -4}}, material: steel}\n");
  EXPECT_TRUE(has(d, 7, 28, "box edges must be positive"));
  EXPECT_TRUE(has(d, 8, 40, "must be a positive length, got 0"));
  EXPECT_TRUE(has(d, 9, 53, "must be a positive length, got -4"));
}

TEST(SceneValidation, UnknownMaterialWithSuggestion) {
  const Diagnostics d = problems(kHead + kMat + "bodies:\n  - {name: a, shape: {sphere: {radius: 2}}, material: steal}\n");
  EXPECT_TRUE(has(d, 7, 55, "unknown material 'steal' (did you mean 'steel'?)"));
}

TEST(SceneValidation, PermanentMaterialWithoutDirection) {
  const Diagnostics d = problems(kHead + kMat + "bodies:\n  - {name: a, shape: {sphere: {radius: 2}}, material: N42}\n");
  EXPECT_TRUE(has(d, 7, 5, "needs a magnetization direction"));
  const Diagnostics p = problems(kHead + kMat +
                                 "bodies:\n"
                                 "  - name: a\n"
                                 "    shape: {sphere: {radius: 2}}\n"
                                 "    material: steel\n"
                                 "    parts:\n"
                                 "      - {shape: {box: [1, 1, 1]}, material: N42}\n");
  EXPECT_TRUE(has(p, 11, 9, "needs a magnetization direction"));
}

TEST(SceneValidation, NonUnitAndZeroQuaternions) {
  const std::string body = "  - {name: a, shape: {sphere: {radius: 2}}, material: steel, orientation: {quat: ";
  EXPECT_TRUE(has(problems(kHead + kMat + "bodies:\n" + body + "[1, 0.1, 0, 0]}}\n"), 7, 82, "not a unit quaternion"));
  EXPECT_TRUE(has(problems(kHead + kMat + "bodies:\n" + body + "[0, 0, 0, 0]}}\n"), 7, 82, "zero quaternion"));
}

TEST(SceneValidation, KeysOutOfTimeOrder) {
  const Diagnostics d = problems(kHead + kMat +
                                 "bodies:\n"
                                 "  - name: a\n"
                                 "    shape: {sphere: {radius: 2}}\n"
                                 "    material: steel\n"
                                 "    motion: kinematic\n"
                                 "    keys:\n"
                                 "      - {t: 0, position: [0, 0, 0]}\n"
                                 "      - {t: 2, position: [0, 0, 1]}\n"
                                 "      - {t: 1, position: [0, 0, 2]}\n");
  EXPECT_TRUE(has(d, 14, 13, "keys out of time order"));
}

TEST(SceneValidation, FramesReversedAndBadSubstep) {
  EXPECT_TRUE(has(problems(kHead + "time: {fps: 24, frames: [100, 1]}\n"), 3, 25, "frame range reversed"));
  EXPECT_TRUE(has(problems(kHead + "time: {fps: 24, dt: 0}\n"), 3, 21, "substep must be positive"));
  EXPECT_TRUE(has(problems(kHead + "time: {fps: 24, dt: -0.001}\n"), 3, 21, "substep must be positive"));
  EXPECT_TRUE(has(problems(kHead + "time: {fps: 24, dt: 0.1}\n"), 3, 21, "must not exceed the frame interval"));
}

TEST(SceneValidation, SleepTimeIsSecondsFromZero) {
  EXPECT_TRUE(has(problems(kHead + "time: {fps: 24, sleep: -1}\n"), 3, 24, "seconds at rest before a body sleeps"));
  EXPECT_TRUE(has(problems(kHead + "time: {fps: 24, sleep: .nan}\n"), 3, 24, "expected a number"));
  EXPECT_TRUE(has(problems(kHead + "time: {fps: 24, sleep: 1e9}\n"), 3, 24, "seconds at rest"));
  EXPECT_DOUBLE_EQ(load_scene_text(kHead + "time: {sleep: 0}\n", "t.yaml").sleep_time, 0.0);
  EXPECT_DOUBLE_EQ(load_scene_text(kHead, "t.yaml").sleep_time, 0.5);
}

TEST(SceneValidation, UnsupportedVersion) {
  EXPECT_TRUE(has(problems("magbake: 2\nunits: {length: m, angle: rad}\n"), 1, 10, "unsupported scene format version 2"));
}

// Format 1.1 is read beside 1; 1.2 is not (yet).
TEST(SceneValidation, Version11IsReadAndLaterOnesAreNot) {
  EXPECT_TRUE(problems("magbake: 1.1\nunits: {length: m, angle: rad}\n").empty());
  EXPECT_TRUE(has(problems("magbake: 1.2\nunits: {length: m, angle: rad}\n"), 1, 10, "reads versions 1 and 1.1"));
}

// Materials carry friction, restitution, damping and colour (format 1.1); a body's own key wins,
// key by key (damping's linear and angular separately).
TEST(SceneValidation, MaterialsCarrySurfaceDampingAndColourThatBodiesOverride) {
  const Scene s = load_scene_text(
      "magbake: 1.1\nunits: {length: mm, angle: deg}\n"
      "materials:\n"
      "  steel: {kind: soft, chi: 700, density: 7850, friction: 0.4, restitution: 0.2, damping: {linear: 0.05, angular: 0.2},"
      " color: [0.5, 0.5, 0.6]}\n"
      "  wood: {kind: none, density: 700}\n"
      "bodies:\n"
      "  - {name: a, shape: {sphere: {radius: 2}}, material: steel}\n"
      "  - {name: b, shape: {sphere: {radius: 2}}, material: steel, friction: 0.9, damping: {angular: 0.7}, color: [1, 0, 0]}\n"
      "  - {name: c, shape: {sphere: {radius: 2}}, material: wood}\n",
      "test.yaml");
  const Body &a = s.bodies[0], &b = s.bodies[1], &c = s.bodies[2];
  EXPECT_EQ(a.friction, 0.4);
  EXPECT_EQ(a.restitution, 0.2);
  EXPECT_EQ(a.linear_damping, 0.05);
  EXPECT_EQ(a.angular_damping, 0.2);
  ASSERT_TRUE(a.color);
  EXPECT_EQ(*a.color, Vec3(0.5, 0.5, 0.6));
  EXPECT_EQ(b.friction, 0.9);
  EXPECT_EQ(b.restitution, 0.2);
  EXPECT_EQ(b.linear_damping, 0.05);
  EXPECT_EQ(b.angular_damping, 0.7);
  EXPECT_EQ(*b.color, Vec3(1, 0, 0));
  EXPECT_EQ(c.friction, 0.5);  // the format's defaults
  EXPECT_EQ(c.restitution, 0.1);
  EXPECT_EQ(c.linear_damping, 0);
  EXPECT_EQ(c.angular_damping, 0);
  EXPECT_FALSE(c.color);
}

TEST(SceneValidation, DampingColourAndMaterialSurfaceKeysOutOfRange) {
  const Diagnostics d = problems(
      "magbake: 1.1\nunits: {length: mm, angle: deg}\n"
      "materials:\n"
      "  steel: {kind: soft, chi: 700, density: 7850, friction: -1, restitution: 2, damping: {linear: 1}, color: [0, 2, 0]}\n"
      "bodies:\n"
      "  - {name: a, shape: {sphere: {radius: 2}}, material: steel, damping: {angular: -0.1}, friction: 101}\n"
      "  - {name: b, shape: {sphere: {radius: 2}}, material: steel, color: [1, 0.5, 1.5]}\n");
  EXPECT_TRUE(has(d, 4, 58, "materials.steel.friction")) << d.format();
  EXPECT_TRUE(has(d, 4, 75, "must be in [0, 1]"));
  EXPECT_TRUE(has(d, 4, 96, "must be in [0, 1): the share of the velocity lost per second"));
  EXPECT_TRUE(has(d, 4, 107, "expected [r, g, b] with each in [0, 1]"));
  EXPECT_TRUE(has(d, 6, 81, "bodies[0].damping.angular"));
  EXPECT_TRUE(has(d, 6, 98, "must be in [0, 100]"));
  EXPECT_TRUE(has(d, 7, 69, "bodies[1].color"));
  EXPECT_EQ(d.items().size(), 7u) << d.format();
}

TEST(SceneValidation, DampingAndColourOfTheWrongShape) {
  const Diagnostics d = problems(
      "magbake: 1.1\nunits: {length: mm, angle: deg}\n" + kMat.substr(0, kMat.find("  steel")) +
      "  steel: {kind: soft, chi: 700, density: 7850}\n"
      "bodies:\n"
      "  - {name: a, shape: {sphere: {radius: 2}}, material: steel, damping: {angular: 0.1, spin: 1}, color: [1, 0]}\n"
      "  - {name: b, shape: {sphere: {radius: 2}}, material: steel, damping: 0.5, color: red}\n");
  EXPECT_TRUE(has(d, 7, 86, "unknown key 'spin'")) << d.format();
  EXPECT_TRUE(has(d, 7, 103, "expected a list of 3 numbers, got 2"));
  EXPECT_TRUE(has(d, 8, 71, "expected a mapping, got '0.5'"));
  EXPECT_TRUE(has(d, 8, 83, "expected a list of 3 numbers"));
}

// Saturation (format 1.1): only soft and linear materials with chi > 0, a positive polarization
// up to 100 T, and the coupled induction; each mistake at its value.
TEST(SceneValidation, SaturationIsChecked) {
  const std::string materials =
      "materials:\n"
      "  N42: {kind: permanent, remanence: 1.3, density: 7500, saturation: 1.0}\n"
      "  copper: {kind: linear, chi: -1.0e-5, density: 8960, saturation: 1.0}\n"
      "  steel: {kind: soft, chi: 700, density: 7850, saturation: -2}\n"
      "  iron: {kind: soft, chi: 700, density: 7850, saturation: 200}\n"
      "  ferrite: {kind: soft, chi: 2000, density: 4800, saturation: 0.4}\n"
      "bodies:\n"
      "  - {name: a, shape: {sphere: {radius: 2}}, material: ferrite}\n";
  const Diagnostics d = problems("magbake: 1.1\nunits: {length: mm, angle: deg}\n" + materials);
  EXPECT_TRUE(has(d, 4, 69, "only soft and linear materials saturate")) << d.format();
  EXPECT_TRUE(has(d, 5, 67, "only a material with chi > 0 saturates"));
  EXPECT_TRUE(has(d, 6, 60, "must be a positive saturation polarization in tesla"));
  EXPECT_TRUE(has(d, 7, 59, "materials.iron.saturation"));
  EXPECT_EQ(d.items().size(), 4u) << d.format();

  const Diagnostics paper = problems(
      "magbake: 1.1\nunits: {length: mm, angle: deg}\nmagnetics: {induction: paper}\n"
      "materials:\n  ferrite: {kind: soft, chi: 2000, density: 4800, saturation: 0.4}\n"
      "bodies:\n  - {name: a, shape: {sphere: {radius: 2}}, material: ferrite}\n");
  EXPECT_TRUE(has(paper, 5, 63, "saturation needs magnetics.induction: coupled")) << paper.format();
  EXPECT_EQ(paper.items().size(), 1u) << paper.format();
}

// Joints (format 1.1): every mistake at its file:line:col.
TEST(SceneValidation, JointsAreCheckedAtTheirPositions) {
  const Diagnostics d = problems(
      "magbake: 1.1\nunits: {length: mm, angle: deg}\n" + kMat +
      "bodies: [{name: needle, shape: {box: [30, 2, 1]}, material: N42, magnetization: [1, 0, 0]},"
      " {name: table, shape: {box: [9, 9, 1]}, material: steel, motion: static}]\n"
      "joints:\n"
      "  - {type: hinge, bodies: [needle], axis: [0, 0, 1]}\n"
      "  - {type: hinj, bodies: [needle], pivot: [0, 0, 0], axis: [0, 0, 1]}\n"
      "  - {type: ball, bodies: [needel], pivot: [0, 0, 0]}\n"
      "  - {type: ball, bodies: [needle, needle], pivot: [0, 0, 0]}\n"
      "  - {type: fixed, bodies: [table]}\n"
      "  - {type: ball, bodies: [needle], pivot: [0, 0, 0], axis: [1, 0, 0]}\n"
      "  - {type: hinge, bodies: [needle], pivot: [0, 0, 0], axis: [0, 0, 1], limits: [10, 20]}\n"
      "  - {type: slider, bodies: [needle], axis: [0, 0, 0]}\n"
      "  - {type: hinge, bodies: [needle], pivot: [0, 0, 0], axis: [0, 0, 1], limits: [-200, 20]}\n"
      "  - {type: fixed, bodies: [needle], limits: [-1, 1]}\n");
  EXPECT_TRUE(has(d, 8, 5, "a hinge joint needs its pivot")) << d.format();
  EXPECT_TRUE(has(d, 9, 12, "unknown joint type 'hinj' (did you mean 'hinge'?)"));
  EXPECT_TRUE(has(d, 10, 26, "unknown body 'needel' (did you mean 'needle'?)"));
  EXPECT_TRUE(has(d, 11, 26, "two different bodies"));
  EXPECT_TRUE(has(d, 12, 27, "a joint holds a dynamic body"));
  EXPECT_TRUE(has(d, 13, 60, "only hinge and slider joints have an axis"));
  EXPECT_TRUE(has(d, 14, 80, "lower <= 0 <= upper"));
  EXPECT_TRUE(has(d, 15, 44, "zero vector"));
  EXPECT_TRUE(has(d, 16, 80, "within [-180, 180] degrees"));
  EXPECT_TRUE(has(d, 17, 45, "only hinge (angles) and slider (lengths) joints have limits"));
  EXPECT_EQ(d.items().size(), 10u) << d.format();
  const Diagnostics p = problems("magbake: 1.1\nunits: {length: mm, angle: deg}\n" + kMat +
                                 "joints:\n"
                                 "  - {type: slider, bodies: [], axis: [1, 0, 0]}\n"
                                 "  - {type: ball, bodies: [a, b, c], pivot: [0, 0, 0], spring: 3}\n"
                                 "  - {bodies: [a]}\n");
  EXPECT_TRUE(has(p, 7, 28, "expected a list of 1 to 2 names")) << p.format();
  EXPECT_TRUE(has(p, 8, 26, "expected a list of 1 to 2 names"));
  EXPECT_TRUE(has(p, 8, 55, "unknown key 'spring'"));
  EXPECT_TRUE(has(p, 9, 5, "missing required key 'type'"));
}

// Animated applied fields (format 1.1): keys and the rotating form, checked where they are written.
TEST(SceneValidation, AnimatedAppliedFieldsAreChecked) {
  const std::string head = "magbake: 1.1\nunits: {length: mm, angle: deg}\n";
  const Diagnostics keys = problems(head + "magnetics:\n  external_field:\n    - {t: 1, B: [0, 0, 200]}\n"
                                           "    - {t: 0.5, B: [0, 0, 0]}\n    - {t: 2, Bx: [0, 0, 1]}\n");
  EXPECT_TRUE(has(keys, 7, 14, "unknown key 'Bx'")) << keys.format();
  EXPECT_TRUE(has(keys, 7, 7, "missing required key 'B'"));
  const Diagnostics ranges = problems(head + "magnetics:\n  external_field:\n    - {t: 1, B: [0, 0, 200]}\n"
                                             "    - {t: 2, B: [0, 0, 0]}\n    - {t: 1.5, B: [0, 0, 0]}\n");
  EXPECT_TRUE(has(ranges, 5, 17, "at most 100 T")) << ranges.format();
  EXPECT_TRUE(has(ranges, 7, 11, "keys out of time order"));
  const Diagnostics rot = problems(head + "magnetics: {external_field: {rotating: {magnitude: -1, frequency: 2, axis: [0, 0, 1], from: [0, 0, 3]}}}\n");
  EXPECT_TRUE(has(rot, 3, 52, "must be >= 0")) << rot.format();
  EXPECT_TRUE(has(rot, 3, 93, "must not be along the axis"));
  const Diagnostics missing = problems(head + "magnetics: {external_field: {rotating: {magnitude: 0.1}, spin: 1}}\n");
  EXPECT_TRUE(has(missing, 3, 40, "missing required key 'frequency'")) << missing.format();
  EXPECT_TRUE(has(missing, 3, 58, "unknown key 'spin'"));
}

TEST(SceneValidation, DuplicateKeys) {
  EXPECT_TRUE(has(problems(kHead + "name: a\nname: b\n"), 4, 1, "duplicate key 'name'"));
  EXPECT_TRUE(has(problems(kHead + "materials:\n  m: {kind: none}\n  m: {kind: none}\n"), 5, 3, "duplicate key 'm'"));
}

TEST(SceneValidation, BadUnitsAndEnumerations) {
  EXPECT_TRUE(has(problems("magbake: 1\nunits: {length: inch, angle: deg}\n"), 2, 17, "expected m, cm or mm"));
  EXPECT_TRUE(has(problems(kHead + "magnetics: {induction: strong}\n"), 3, 24, "expected coupled, paper or off"));
  EXPECT_TRUE(has(problems(kHead + "magnetics: {induction_tolerance: 0}\n"), 3, 34, "must be in [1e-12, 0.1]"));
  EXPECT_TRUE(has(problems(kHead + "magnetics: {induction_tolerance: 0.5}\n"), 3, 34, "must be in [1e-12, 0.1]"));
  EXPECT_TRUE(has(problems(kHead + "magnetics: {induction_tolerance: .nan}\n"), 3, 34, ""));
  EXPECT_TRUE(has(problems(kHead + "materials:\n  m: {kind: permanant, remanence: 1}\n"), 4, 13, "did you mean 'permanent'"));
}

TEST(SceneValidation, DynamicBodyNeedsAMass) {
  const Diagnostics d = problems(kHead + "materials:\n  m: {kind: soft, chi: 5}\nbodies:\n  - {name: a, shape: {sphere: {radius: 2}}, material: m}\n");
  EXPECT_TRUE(has(d, 6, 5, "a dynamic body needs a mass"));
}

TEST(SceneValidation, SyntaxErrorHasAPosition) {
  const Diagnostics d = problems(kHead + "bodies: [\n");
  ASSERT_FALSE(d.empty());
  EXPECT_GT(d.items()[0].loc.line, 0);
  EXPECT_NE(d.items()[0].message.find("YAML syntax error"), std::string::npos);
}

class MeshFiles : public ::testing::Test {
 protected:
  std::filesystem::path dir = magbake::testing::fresh_temp_dir("magbake_scene_test");
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return (dir / name).string();
  }
};

TEST_F(MeshFiles, UnreadableMesh) {
  const std::string scene = write("s.yaml", kHead + kMat +
                                                "bodies:\n  - {name: a, shape: {mesh: {file: nowhere.obj}}, material: steel}\n");
  try {
    load_scene(scene);
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_TRUE(has(e.diagnostics(), 7, 36, "cannot read mesh"));
  }
}

TEST_F(MeshFiles, NonClosedMesh) {
  // A tetrahedron with one face missing.
  write("open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n");
  const std::string scene = write("s.yaml", kHead + kMat +
                                                "bodies:\n  - {name: a, shape: {mesh: {file: open.obj}}, material: steel}\n");
  try {
    load_scene(scene);
    FAIL();
  } catch (const SceneError& e) {
    EXPECT_TRUE(has(e.diagnostics(), 7, 36, "mesh is not closed: 3 boundary edges"));
  }
}

TEST_F(MeshFiles, MeshPathsAreRelativeToTheSceneFile) {
  write("tet.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n");
  const std::string scene = write("s.yaml", kHead + kMat +
                                                "bodies:\n  - {name: a, shape: {mesh: {file: tet.obj, scale: 10}}, material: steel}\n");
  const Scene s = load_scene(scene);
  // Unit tetrahedron x 10 mm: volume 1000/6 mm³.
  EXPECT_NEAR(s.bodies[0].shape.shape->volume(), 1000.0 / 6 * 1e-9, 1e-18);
  EXPECT_NEAR(s.bodies[0].mass, 7850 * 1000.0 / 6 * 1e-9, 1e-12);
}

}  // namespace
}  // namespace magbake::scene
