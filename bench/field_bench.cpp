// Field export speed and accuracy: B on a 128³ or 256³ voxel grid around a scene of > 4000
// cells (the horseshoe mesh magnet, N42, and 24 steel balls), by the tree code (what
// `magbake field` runs: theta 0.25, single precision) and by direct summation (theta 0).
//
//   field_bench <resolution> <tree|direct> [theta] [threshold]   -> one CSV line on stdout
// (theta default 0.15, magbake field's default, and threshold 1e-5 T). The field is saved as raw
// float32 triples (NaN = inactive) to /tmp/magbake_field_bench_<resolution>_<mode>_<theta>.f32.
// Run each case in its own process (bench/run_field_bench.sh) so peak memory is per case.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "field_export.h"
#include "geometry/mesh_import.h"
#include "geometry/shapes.h"
#include "io/field_volume.h"
#include "magnetics/system.h"

using namespace magbake;
using magnetics::Vec3;

int main(int argc, char** argv) {
  const int res = argc > 1 ? std::atoi(argv[1]) : 128;
  const std::string mode = argc > 2 ? argv[2] : "tree";
  const double theta = argc > 3 ? std::atof(argv[3]) : 0.15;  // magbake field's default
  const double threshold = argc > 4 ? std::atof(argv[4]) : 1e-5;
  // Scene: horseshoe magnet (mm mesh -> m) and a ring of steel balls.
  geometry::TriangleSoup soup = geometry::load_triangles(std::string(MAGBAKE_SOURCE_DIR) + "/scenes/meshes/horseshoe.obj", 1e-3);
  geometry::MeshShape horseshoe(std::move(soup.vertices), std::move(soup.triangles));
  geometry::SphereShape ball(0.003);
  magnetics::Material n42;
  n42.kind = magnetics::MaterialKind::kPermanent;
  n42.remanence = 1.3;
  n42.direction = Vec3(1, 0, 0);
  magnetics::Material steel;
  steel.kind = magnetics::MaterialKind::kLinear;
  steel.chi = 700;
  std::vector<magnetics::BodySpec> bodies(25);
  bodies[0].parts.push_back({&horseshoe, {}, n42, 0.0011});
  for (int i = 1; i < 25; ++i) bodies[i].parts.push_back({&ball, {}, steel, 0.0015});
  magnetics::BuildSettings bs;
  const magnetics::Model model = magnetics::build_model(bodies, bs);
  magnetics::State st;
  st.resize(model);
  for (int i = 1; i < 25; ++i) {
    const double a = 2 * M_PI * i / 24;
    st.body_pose[i].position = Vec3(0.03 * std::cos(a), 0.03 * std::sin(a), 0.005 * (i % 3));
  }
  magnetics::Settings settings;
  magnetics::Result result;
  magnetics::evaluate(model, settings, st, result);  // induced moments of the balls
  // Region: the bodies plus 1 cm.
  const Vec3 lo(-0.045, -0.045, -0.03), hi(0.045, 0.045, 0.035);
  io::FieldSamples samples;
  samples.voxel = (hi - lo).maxCoeff() / (res - 1);
  samples.origin = lo;
  samples.dims = ((hi - lo) / samples.voxel).array().round().cast<int>() + 1;
  samples.dims = samples.dims.cwiseMin(res);
  magnetics::FieldOptions opt;
  opt.theta = mode == "direct" ? 0.0 : theta;
  opt.near_field = settings.near_field;
  opt.smear_inside = true;
  opt.single_precision = true;
  const auto t0 = std::chrono::steady_clock::now();
  cli::evaluate_field_grid(model, st, opt, threshold, samples);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::size_t evaluated = 0;
  for (float x : samples.bx) evaluated += !std::isnan(x);
  // Save the field for the error comparison (raw float32 triples, NaN = skipped).
  char tag[32];
  std::snprintf(tag, sizeof tag, "%g", opt.theta);
  const std::string raw = "/tmp/magbake_field_bench_" + std::to_string(res) + "_" + mode + "_" + tag + ".f32";
  FILE* f = std::fopen(raw.c_str(), "wb");
  for (std::size_t q = 0; q < samples.bx.size(); ++q) {
    const float v[3] = {samples.bx[q], samples.by[q], samples.bz[q]};
    std::fwrite(v, sizeof v, 1, f);
  }
  std::fclose(f);
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  std::printf("%d,%s,%g,%g,%d,%d,%d,%zu,%.3f,%.4g,%.1f\n", res, mode.c_str(), opt.theta, threshold, samples.dims[0],
              samples.dims[1], samples.dims[2], evaluated, seconds, evaluated / seconds, ru.ru_maxrss / 1024.0);
  std::fprintf(stderr, "cells %d, voxels %zu evaluated in %.2f s\n", model.cell_count(), evaluated, seconds);
  return 0;
}
