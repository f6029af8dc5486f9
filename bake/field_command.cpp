// magbake field: B-field volumes (OpenVDB) from a cache, frame by frame.
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cli.h"
#include "field_export.h"
#include "io/cache.h"
#include "io/field_volume.h"
#include "magnetics/system.h"
#include "progress.h"

namespace magbake::cli {
namespace fs = std::filesystem;
using magnetics::Vec3;

std::string expand_pattern(const std::string& pattern, int frame) {
  // "####" (any run of #) -> zero-padded frame; otherwise a printf %d / %04d style pattern.
  const auto h = pattern.find('#');
  if (h != std::string::npos) {
    std::size_t n = 0;
    while (h + n < pattern.size() && pattern[h + n] == '#') ++n;
    char buf[32];
    std::snprintf(buf, sizeof buf, "%0*d", static_cast<int>(n), frame);
    return pattern.substr(0, h) + buf + pattern.substr(h + n);
  }
  if (pattern.find('%') != std::string::npos) {
    char buf[4096];
    std::snprintf(buf, sizeof buf, pattern.c_str(), frame);
    return buf;
  }
  // No frame token: add one before the extension.
  const fs::path p(pattern);
  return (p.parent_path() / (p.stem().string() + "." + std::to_string(frame) + p.extension().string())).string();
}

namespace {

// Axis-aligned bounds of the magnetic bodies over every frame of the cache (world, m).
magnetics::Box3 magnetic_bounds(const io::CacheReader& cache, const magnetics::Model& model) {
  const hid_t f = cache.file();
  const auto verts = io::h5::read_doubles(f, "geometry/vertices");
  const auto body = io::h5::read_ints(f, "geometry/submesh_body");
  const auto vb = io::h5::read_ints(f, "geometry/submesh_vertex_begin");
  const auto vc = io::h5::read_ints(f, "geometry/submesh_vertex_count");
  magnetics::Box3 box;
  for (int i = 0; i < cache.frame_count(); ++i) {
    const io::CacheFrame fr = cache.frame(i);
    for (std::size_t s = 0; s < body.size(); ++s) {
      const int b = static_cast<int>(body[s]);
      if (model.body_root[b] < 0) continue;  // not magnetic
      for (std::int64_t v = vb[s]; v < vb[s] + vc[s]; ++v) {
        const Vec3 p(verts[3 * v], verts[3 * v + 1], verts[3 * v + 2]);
        box.extend(fr.position[b] + fr.orientation[b] * p);
      }
    }
  }
  return box;
}

}  // namespace

int export_field(const std::string& cache_path, const FieldRequest& req, const Global& g) {
  std::optional<io::CacheReader> cache;
  try {
    cache.emplace(cache_path);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return kUsage;
  }
  std::optional<scene::FieldOutput> field;
  std::optional<scene::PreviewOutput> preview;
  scene::outputs_of_text(cache->scene_text(), field, preview);
  const scene::FieldOutput defaults = field.value_or(scene::FieldOutput{});

  // Frames.
  if (cache->frame_count() == 0) {
    spdlog::error("{} holds no complete frame", cache_path);
    return kUsage;
  }
  const int first = cache->frame(0).frame, last = cache->frame(cache->frame_count() - 1).frame;
  int a = first, b = last;
  if (req.frames) {
    a = req.frames->first, b = req.frames->second;
    if (a > b || a < first || b > last) {
      spdlog::error("--frames {}-{} is outside the cache's frames {}-{}", a, b, first, last);
      return kUsage;
    }
  }
  const int every = req.every.value_or(field ? defaults.every : 1);

  // Output pattern, checked writable before any work.
  std::string pattern = req.pattern.empty() ? (field ? defaults.path : "") : req.pattern;
  if (pattern.empty()) pattern = (fs::path(cache_path).parent_path() / (fs::path(cache_path).stem().string() + ".####.vdb")).string();
  const fs::path out_dir = fs::path(expand_pattern(pattern, a)).parent_path();
  std::error_code ec;
  if (!out_dir.empty()) fs::create_directories(out_dir, ec);
  {
    const fs::path probe = (out_dir.empty() ? fs::path(".") : out_dir) / ".magbake_write_test";
    std::ofstream test(probe);
    if (ec || !test) {
      spdlog::error("cannot write field volumes to '{}': the folder is not writable", (out_dir.empty() ? fs::path(".") : out_dir).string());
      return kUsage;
    }
    test.close();
    fs::remove(probe, ec);
  }

  std::vector<int> induced_order;
  const magnetics::Model model = cache->model(&induced_order);
  if (model.empty()) {
    spdlog::warn("{}: no magnetic bodies: no field volumes written", cache_path);
    return kOk;
  }

  // Region and voxel size (fixed for the whole cache, so split frame ranges line up).
  magnetics::Box3 region;
  if (req.bounds) {
    region = *req.bounds;
  } else if (field && !defaults.auto_bounds) {
    region = magnetics::Box3(defaults.bounds_min, defaults.bounds_max);
  } else {
    region = magnetic_bounds(*cache, model);
    const double margin = req.margin.value_or(defaults.margin);
    region.min() -= Vec3::Constant(margin);
    region.max() += Vec3::Constant(margin);
  }
  const double voxel = req.voxel.value_or(field && defaults.voxel ? *defaults.voxel : region.sizes().maxCoeff() / 128.0);
  if (!(voxel > 0)) {
    spdlog::error("the voxel size must be positive");
    return kUsage;
  }
  // Voxel centres on multiples of the voxel size (frames and split runs share one lattice).
  const Eigen::Vector3d lo = (region.min() / voxel).array().floor() * voxel;
  const Eigen::Vector3d hi = (region.max() / voxel).array().ceil() * voxel;
  const Eigen::Vector3i dims = ((hi - lo) / voxel).array().round().cast<int>() + 1;
  const double nvox = double(dims[0]) * dims[1] * dims[2];
  if (nvox > double(req.max_voxels)) {
    spdlog::error("{} x {} x {} voxels ({:.3g}) exceeds the limit of {:.3g}: raise --voxel (now {} m)", dims[0], dims[1],
                  dims[2], nvox, double(req.max_voxels), voxel);
    return kUsage;
  }
  const double threshold = req.threshold;
  const std::vector<double> ext = cache->parameter_doubles("external_field");
  const Vec3 applied(ext.at(0), ext.at(1), ext.at(2));
  magnetics::FieldOptions opt;
  opt.theta = req.theta;
  opt.near_field = cache->parameter_doubles("near_field").at(0);
  opt.smear_inside = true;
  opt.single_precision = true;

  spdlog::info("field volumes: {} x {} x {} voxels of {:.4g} mm over [{:.4g} {:.4g} {:.4g}]-[{:.4g} {:.4g} {:.4g}] m, "
               "frames {}-{} every {}",
               dims[0], dims[1], dims[2], voxel * 1e3, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], a, b, every);
  const auto coms = cache->centers_of_mass();
  magnetics::State st;
  st.resize(model);
  Progress progress("field", (b - a) / every + 1, g.quiet);
  int done = 0;
  for (int i = 0; i < cache->frame_count(); ++i) {
    const io::CacheFrame fr = cache->frame(i);
    if (fr.frame < a || fr.frame > b || (fr.frame - a) % every != 0) continue;
    if (interrupt_requested()) {
      progress.finish();
      spdlog::warn("interrupted after {} volumes", done);
      return kInterrupted;
    }
    // Poses (centre-of-mass frames) and the stored induced moments.
    for (int body = 0; body < model.body_count; ++body) {
      st.body_pose[body] = magnetics::Pose{fr.orientation[body], fr.position[body] + fr.orientation[body] * coms[body]};
    }
    std::vector<Vec3> induced(model.induced_cells.size());
    for (std::size_t k = 0; k < induced.size(); ++k) induced[k] = fr.induced_moment.at(induced_order[k]);
    magnetics::place(model, st, induced);
    io::FieldSamples samples;
    samples.origin = lo;
    samples.voxel = voxel;
    samples.dims = dims;
    evaluate_field_grid(model, st, opt, applied, threshold, samples);
    io::VolumeInfo info;
    info.frame = fr.frame;
    info.time = fr.time;
    info.scene_hash = cache->scene_hash();
    info.scene_name = cache->attribute("scene_name");
    info.threshold = threshold;
    const std::string path = expand_pattern(pattern, fr.frame);
    try {
      const std::size_t active = io::write_field_volume(path, samples, info);
      spdlog::debug("{}: {} active voxels", path, active);
    } catch (const std::exception& e) {
      progress.finish();
      spdlog::error("{}", e.what());
      return kFailure;
    }
    ++done;
    progress.update(done, "frame " + std::to_string(fr.frame));
  }
  progress.finish();
  spdlog::info("wrote {} field volumes ({})", done, pattern);
  return kOk;
}

}  // namespace magbake::cli
