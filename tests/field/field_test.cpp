// magbake field: OpenVDB volumes read back with OpenVDB and pyopenvdb, compared with probe.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <openvdb/openvdb.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <iomanip>
#include <sstream>

#include "support/shell.h"

namespace magbake::testing {
namespace {
namespace fs = std::filesystem;

std::string exe() { return MAGBAKE_EXE; }
std::string src(const std::string& rel) { return std::string(MAGBAKE_SOURCE_DIR) + "/" + rel; }

class Field : public ::testing::Test {
 protected:
  fs::path dir;
  void SetUp() override {
    openvdb::initialize();
    dir = fresh_temp_dir("magbake_field_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir);  // kept for a look when the test failed
  }
  openvdb::GridPtrVecPtr read(const fs::path& p, openvdb::MetaMap::Ptr* meta = nullptr) {
    openvdb::io::File f(p.string());
    f.open();
    auto grids = f.getGrids();
    if (meta) *meta = f.getMetadata();
    f.close();
    return grids;
  }
};

TEST_F(Field, VolumesHaveTheConventionsRenderersExpect) {
  const std::string cache = src("tests/golden/sphere_pickup.h5");
  ASSERT_EQ(sh(exe() + " field " + cache + " --frames 1-3 --voxel 0.001 -o " + (dir / "f.####.vdb").string()).code, 0);
  for (int f = 1; f <= 3; ++f) ASSERT_TRUE(fs::exists(dir / ("f.000" + std::to_string(f) + ".vdb")));
  openvdb::MetaMap::Ptr meta;
  auto grids = read(dir / "f.0002.vdb", &meta);
  ASSERT_EQ(grids->size(), 2u);
  auto B = openvdb::gridPtrCast<openvdb::Vec3SGrid>((*grids)[0]);
  auto density = openvdb::gridPtrCast<openvdb::FloatGrid>((*grids)[1]);
  ASSERT_TRUE(B && density);
  EXPECT_EQ(B->getName(), "B");
  EXPECT_EQ(density->getName(), "density");
  EXPECT_EQ(B->getVectorType(), openvdb::VEC_CONTRAVARIANT_RELATIVE);
  EXPECT_EQ(B->getGridClass(), openvdb::GRID_UNKNOWN);
  EXPECT_NEAR(B->voxelSize()[0], 0.001, 1e-15);
  EXPECT_TRUE(B->transform().isLinear());
  EXPECT_EQ(meta->metaValue<std::string>("creator"), "magbake");
  EXPECT_EQ(meta->metaValue<int>("frame"), 2);
  EXPECT_NEAR(meta->metaValue<double>("time"), 1.0 / 30, 1e-12);
  EXPECT_EQ(meta->metaValue<std::string>("scene_hash").size(), 64u);
  EXPECT_EQ(B->metaValue<std::string>("units"), "tesla");
  EXPECT_GT(B->activeVoxelCount(), 1000u);
  EXPECT_EQ(B->activeVoxelCount(), density->activeVoxelCount());
  // Sparse: the background is zero and inactive voxels are below the threshold.
  EXPECT_EQ(B->background(), openvdb::Vec3s(0, 0, 0));
  for (auto it = density->cbeginValueOn(); it; ++it) {
    ASSERT_GE(*it, 0.0f);
    ASSERT_LE(*it, 1.0f);
  }
}

// Volume values against `magbake probe` at voxel centres outside the bodies (frame 1 is the
// scene's initial state, which probe evaluates at --time 0). The scene asks for theta 0: probe
// sums every cell directly, field export uses its tree (--theta default 0.15) and single precision, so
// the difference is field export's error (documented bound: 1e-3 RMS relative).
TEST_F(Field, VoxelValuesMatchProbe) {
  std::ifstream in(src("tests/golden/sphere_pickup.yaml"));
  std::string text((std::istreambuf_iterator<char>(in)), {});
  text.replace(text.find("quality: draft"), 14, "quality: draft, theta: 0");
  text.replace(text.find("frames: [1, 25]"), 15, "frames: [1, 2]");
  const std::string scene = (dir / "sphere_pickup.yaml").string();
  std::ofstream(scene) << text;
  ASSERT_EQ(sh(exe() + " bake " + scene + " -o " + dir.string()).code, 0);
  const std::string cache = (dir / "sphere_pickup.h5").string();
  ASSERT_EQ(sh(exe() + " field " + cache + " --frames 1-1 --voxel 0.001 -o " + (dir / "v.####.vdb").string()).code, 0);
  auto grids = read(dir / "v.0001.vdb");
  auto B = openvdb::gridPtrCast<openvdb::Vec3SGrid>((*grids)[0]);
  // Sample active voxels at least 2 mm from the ball (r 4 mm at z 4 mm) and the magnet
  // (r 5, h 8 at z 30 mm) and above the plate.
  std::vector<openvdb::Coord> coords;
  std::mt19937 rng(4);
  for (auto it = B->cbeginValueOn(); it; ++it) {
    const openvdb::Vec3d x = B->indexToWorld(it.getCoord());
    const double to_ball = std::hypot(x[0], x[1], x[2] - 0.004) - 0.004;
    const double rho = std::hypot(x[0], x[1]);
    const double to_magnet = std::max(rho - 0.005, std::abs(x[2] - 0.030) - 0.004);
    if (to_ball > 0.002 && to_magnet > 0.002 && x[2] > 0.001 && (rng() % 50 == 0)) coords.push_back(it.getCoord());
  }
  ASSERT_GT(coords.size(), 30u);
  std::ofstream pts(dir / "points.txt");
  for (const auto& c : coords) {
    const openvdb::Vec3d x = B->indexToWorld(c);
    pts << std::setprecision(17) << x[0] << " " << x[1] << " " << x[2] << "\n";
  }
  pts.close();
  const Outcome p = sh(exe() + " probe " + scene + " --points " + (dir / "points.txt").string() + " --json 2>/dev/null");
  ASSERT_EQ(p.code, 0) << p.out;
  const auto j = nlohmann::json::parse(p.out.substr(0, p.out.rfind('}') + 1));
  auto acc = B->getConstAccessor();
  double num = 0, den = 0, worst = 0;
  for (std::size_t i = 0; i < coords.size(); ++i) {
    const openvdb::Vec3s v = acc.getValue(coords[i]);
    const Eigen::Vector3d ref(j["B"][i][0].get<double>(), j["B"][i][1].get<double>(), j["B"][i][2].get<double>());
    const Eigen::Vector3d got(v[0], v[1], v[2]);
    num += (got - ref).squaredNorm();
    den += ref.squaredNorm();
    worst = std::max(worst, (got - ref).norm() / ref.norm());
  }
  EXPECT_LT(std::sqrt(num / den), 1e-3);
  EXPECT_LT(worst, 1e-2);
  std::printf("%zu voxels: RMS relative difference %.2e, worst %.2e\n", coords.size(), std::sqrt(num / den), worst);
}

// The accuracy docs/field-volumes.md claims for the default opening angle: against direct
// summation (--theta 0), the 99.9th percentile of the relative error where |B| > 1 mT stays under
// 0.5% and the RMS relative error under 1e-3. bench/field_bench's scene (its horseshoe and a ring
// of steel balls) with the magnet's surface off, so that cells carry every field and the tree's
// far aggregates decide the error: measured 0.10% at theta 0.15, 0.96% at the old 0.25.
TEST_F(Field, DefaultThetaKeepsTheWorstVoxelsWithinHalfAPercentOfDirectSummation) {
  std::ostringstream scene;
  scene << "magbake: 1\nname: horseshoe\nunits: {length: mm, angle: deg}\n"
           "time: {fps: 30, frames: [1, 2], dt: 0.001}\nmagnetics: {surface_tolerance: 0}\n"
           "materials:\n  N42: {kind: permanent, remanence: 1.3, density: 7500}\n"
           "  steel: {kind: soft, chi: 700, density: 7850}\n"
           "bodies:\n  - {name: magnet, shape: {mesh: {file: "
        << src("scenes/meshes/horseshoe.obj")
        << "}}, material: N42, magnetization: [1, 0, 0], motion: static}\n";
  for (int i = 0; i < 8; ++i) {
    const double a = 2 * M_PI * (i + 0.5) / 8;
    scene << "  - {name: ball" << i << ", shape: {sphere: {radius: 3}}, material: steel, motion: static, position: ["
          << 30 * std::cos(a) << ", " << 30 * std::sin(a) << ", " << 5 * (i % 3) << "]}\n";
  }
  const std::string path = (dir / "horseshoe.yaml").string();
  std::ofstream(path) << scene.str();
  ASSERT_EQ(sh(exe() + " bake " + path + " -o " + dir.string()).code, 0);
  const std::string cache = (dir / "horseshoe.h5").string();
  const std::string region = " --frames 1-1 --voxel 0.0008 --bounds=-0.045,-0.045,-0.02,0.045,0.045,0.03";
  ASSERT_EQ(sh(exe() + " field " + cache + region + " -o " + (dir / "tree.####.vdb").string()).code, 0);
  ASSERT_EQ(sh(exe() + " field " + cache + region + " --theta 0 -o " + (dir / "direct.####.vdb").string()).code, 0);
  auto tree = openvdb::gridPtrCast<openvdb::Vec3SGrid>((*read(dir / "tree.0001.vdb"))[0]);
  auto direct = openvdb::gridPtrCast<openvdb::Vec3SGrid>((*read(dir / "direct.0001.vdb"))[0]);
  ASSERT_TRUE(tree && direct);
  auto acc = tree->getConstAccessor();
  std::vector<double> rel;
  double num = 0, den = 0;
  for (auto it = direct->cbeginValueOn(); it; ++it) {
    const openvdb::Vec3s d = *it, t = acc.getValue(it.getCoord());
    const double e = (t - d).length(), m = d.length();
    num += e * e, den += m * m;
    if (m > 1e-3) rel.push_back(e / m);
  }
  ASSERT_GT(rel.size(), 500000u);
  std::sort(rel.begin(), rel.end());
  const double p999 = rel[static_cast<std::size_t>(0.999 * (rel.size() - 1))];
  std::printf("%zu voxels above 1 mT: relative error p99.9 %.2e, max %.2e; RMS %.2e\n", rel.size(), p999, rel.back(),
              std::sqrt(num / den));
  EXPECT_LT(p999, 0.005);
  EXPECT_LT(std::sqrt(num / den), 1e-3);
}

TEST_F(Field, SplitFrameRangesGiveTheSameVolumes) {
  const std::string cache = src("tests/golden/sphere_pickup.h5");
  ASSERT_EQ(sh(exe() + " field " + cache + " --frames 2-7 --voxel 0.002 -o " + (dir / "all/f.####.vdb").string()).code, 0);
  ASSERT_EQ(sh(exe() + " field " + cache + " --frames 2-4 --voxel 0.002 -o " + (dir / "a/f.####.vdb").string()).code, 0);
  ASSERT_EQ(sh(exe() + " field " + cache + " --frames 5-7 --voxel 0.002 -o " + (dir / "b/f.####.vdb").string()).code, 0);
  for (int f = 2; f <= 7; ++f) {
    const std::string name = "f.000" + std::to_string(f) + ".vdb";
    auto whole = openvdb::gridPtrCast<openvdb::Vec3SGrid>((*read(dir / "all" / name))[0]);
    auto part = openvdb::gridPtrCast<openvdb::Vec3SGrid>((*read(dir / (f <= 4 ? "a" : "b") / name))[0]);
    ASSERT_EQ(whole->activeVoxelCount(), part->activeVoxelCount()) << name;
    auto acc = part->getConstAccessor();
    for (auto it = whole->cbeginValueOn(); it; ++it) {
      ASSERT_EQ(*it, acc.getValue(it.getCoord())) << name << " " << it.getCoord();
      ASSERT_TRUE(acc.isValueOn(it.getCoord()));
    }
  }
}

TEST_F(Field, ReadableByPyopenvdb) {
  const std::string cache = src("tests/golden/sphere_pickup.h5");
  ASSERT_EQ(sh(exe() + " field " + cache + " --frames 3-3 --voxel 0.002 -o " + (dir / "p.####.vdb").string()).code, 0);
  const Outcome r = sh("/usr/bin/python3 " + src("tests/field/read_vdb.py") + " " + (dir / "p.0003.vdb").string());
  EXPECT_EQ(r.code, 0) << r.out;
}

TEST_F(Field, NoMagneticBodiesBadRangesAndUnwritablePaths) {
  // A scene without magnets bakes; its field export writes nothing and says so.
  std::ofstream(dir / "plain.yaml") << "magbake: 1\nunits: {length: mm, angle: deg}\ntime: {fps: 30, frames: [1, 3]}\n"
                                       "materials: {wood: {kind: none, density: 600}}\n"
                                       "bodies: [{name: block, shape: {box: [10, 10, 10]}, material: wood}]\n";
  ASSERT_EQ(sh(exe() + " bake " + (dir / "plain.yaml").string() + " -o " + dir.string()).code, 0);
  const Outcome none = sh(exe() + " field " + (dir / "plain.h5").string() + " -o " + (dir / "x.####.vdb").string());
  EXPECT_EQ(none.code, 0);
  EXPECT_NE(none.out.find("no magnetic bodies: no field volumes written"), std::string::npos) << none.out;
  EXPECT_TRUE(fs::is_empty(dir) || !fs::exists(dir / "x.0001.vdb"));
  const std::string cache = src("tests/golden/sphere_pickup.h5");
  EXPECT_EQ(sh(exe() + " field " + cache + " --frames 9-3").code, 2);
  EXPECT_EQ(sh(exe() + " field " + cache + " --frames 1-999").code, 2);
  std::ofstream(dir / "a_file") << "x";
  const Outcome bad = sh(exe() + " field " + cache + " --frames 1-1 -o " + (dir / "a_file/f.####.vdb").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.out.find("not writable"), std::string::npos) << bad.out;
  EXPECT_EQ(sh(exe() + " field " + (dir / "missing.h5").string()).code, 2);
  // Nothing half-written under a final name: only complete .vdb files, no temporaries.
  for (const auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos);
}

TEST(PatternExpansion, HashesAndPrintf) {
  // Through the binary: -o with %04d gives the same names as ####.
  const fs::path d = fresh_temp_dir("magbake_field_pattern");
  const std::string cache = src("tests/golden/sphere_pickup.h5");
  ASSERT_EQ(sh(exe() + " field " + cache + " --frames 12-12 --voxel 0.003 -o " + (d / "a.%04d.vdb").string()).code, 0);
  ASSERT_EQ(sh(exe() + " field " + cache + " --frames 12-12 --voxel 0.003 -o " + (d / "b.##.vdb").string()).code, 0);
  EXPECT_TRUE(fs::exists(d / "a.0012.vdb"));
  EXPECT_TRUE(fs::exists(d / "b.12.vdb"));
}

}  // namespace
}  // namespace magbake::testing
