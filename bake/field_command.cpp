// magbake field: B-field volumes (OpenVDB) from a cache, frame by frame.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cache_export.h"
#include "cli.h"
#include "field_export.h"
#include "field_lines.h"
#include "io/cache.h"
#include "io/field_volume.h"
#include "magnetics/system.h"
#include "progress.h"

namespace magbake::cli {
namespace fs = std::filesystem;
using magnetics::Vec3;

namespace {

// What auto bounds need from every frame of the cache: the axis-aligned box of the magnetic
// bodies (world, m), and the margin at which the strongest body's field has fallen to the
// threshold (m; 0 when no body's field reaches beyond its bounding sphere).
struct MagneticExtent {
  magnetics::Box3 box;
  double reach = 0;
};

// Each magnetic body's net moment (its permanent cells turned with it plus its stored induced
// moments) at each frame gives the distance d from the centre of its mesh at which its dipole
// field on the axis, 2 (mu0 / 4 pi) |m| / d³, equals `threshold`; the reach is the largest
// d - r over bodies and frames, r the mesh's radius about that centre.
MagneticExtent magnetic_extent(const io::CacheReader& cache, const magnetics::Model& model,
                               const std::vector<int>& induced_order, double threshold) {
  const io::RenderGeometry geo = cache.geometry();
  const int nb = model.body_count;
  // Per body: centre and radius of its meshes (body frame).
  std::vector<magnetics::Box3> local(nb);
  for (const io::RenderGeometry::Submesh& s : geo.submeshes) {
    for (std::int64_t v = s.vertex_begin; v < s.vertex_begin + s.vertex_count; ++v) local[s.body].extend(geo.vertices[v]);
  }
  std::vector<double> radius(nb, 0.0);
  for (const io::RenderGeometry::Submesh& s : geo.submeshes) {
    for (std::int64_t v = s.vertex_begin; v < s.vertex_begin + s.vertex_count; ++v) {
      radius[s.body] = std::max(radius[s.body], (geo.vertices[v] - local[s.body].center()).norm());
    }
  }
  const std::vector<Vec3> permanent = body_permanent_moments(model);
  MagneticExtent out;
  for (int i = 0; i < cache.frame_count(); ++i) {
    const io::CacheFrame fr = cache.frame(i);
    const std::vector<Vec3> net = body_moments(model, permanent, induced_order, fr);
    for (const io::RenderGeometry::Submesh& s : geo.submeshes) {
      if (model.body_root[s.body] < 0) continue;  // not magnetic
      for (std::int64_t v = s.vertex_begin; v < s.vertex_begin + s.vertex_count; ++v) {
        out.box.extend(fr.position[s.body] + fr.orientation[s.body] * geo.vertices[v]);
      }
    }
    for (int b = 0; b < nb; ++b) {
      if (model.body_root[b] < 0 || local[b].isEmpty()) continue;
      const double d = std::cbrt(2.0 * magnetics::kMu0Over4Pi * net[b].norm() / threshold);
      out.reach = std::max(out.reach, d - radius[b]);
    }
  }
  return out;
}

}  // namespace

int export_field(const std::string& cache_path, const FieldRequest& req, const Global& g) {
  std::optional<io::CacheReader> cache;
  int a = 0, b = 0;
  if (const int rc = open_cache_range(cache_path, req.frames, cache, a, b); rc != kOk) return rc;
  std::optional<scene::FieldOutput> field;
  std::optional<scene::PreviewOutput> preview;
  if (const int rc = stored_outputs(*cache, !req.pattern.empty(), field, preview); rc != kOk) return rc;
  const scene::FieldOutput defaults = field.value_or(scene::FieldOutput{});

  const int every = req.every.value_or(field ? defaults.every : 1);

  // Output pattern, checked writable before any work. One from the scene stays in the folder.
  std::string pattern = req.pattern.empty() ? (field ? defaults.path : "") : req.pattern;
  if (req.pattern.empty() && !pattern.empty()) {
    if (const int rc = check_scene_output_path(pattern, req.allow_absolute, "outputs.field.path"); rc != kOk) return rc;
  }
  if (pattern.empty()) pattern = (fs::path(cache_path).parent_path() / (fs::path(cache_path).stem().string() + ".####.vdb")).string();
  if (const int rc = prepare_output_folder(pattern, a, "field volumes"); rc != kOk) return rc;

  std::vector<int> induced_order;
  const magnetics::Model model = cache->model(&induced_order);
  if (model.empty()) {
    spdlog::warn("{}: no magnetic bodies: no field volumes written", cache_path);
    return kOk;
  }

  // Threshold and display density, relative to the strongest field the shot's sources make:
  // the largest remanence of its magnets (the field at a long magnet's pole face), or the
  // applied field's strength if that is larger (soft bodies in a coil).
  double max_magnetization = 0;
  for (const Vec3& M : model.part_magnetization) max_magnetization = std::max(max_magnetization, M.norm());
  // The applied field may change from frame to frame (scene 1.1): its strongest value.
  double applied_max = 0;
  for (int i = 0; i < cache->frame_count(); ++i) applied_max = std::max(applied_max, cache->applied_field(i).norm());
  double reference = std::max(magnetics::kMu0 * max_magnetization, applied_max);
  if (!(reference > 0)) reference = 1.0;  // no source: no field anywhere, nothing active
  double threshold = io::kAutoThresholdFraction * reference;
  if (req.threshold) threshold = *req.threshold;
  else if (!req.threshold_auto && field && defaults.threshold) threshold = *defaults.threshold;

  // Region and voxel size (fixed for the whole cache, so split frame ranges line up).
  magnetics::Box3 region;
  if (req.bounds) {
    region = *req.bounds;
  } else if (field && !defaults.auto_bounds) {
    region = magnetics::Box3(defaults.bounds_min, defaults.bounds_max);
  } else {
    // Auto: the magnetic bodies over the whole shot, plus the margin; an auto margin reaches
    // where the strongest body's field falls to the threshold, at least a quarter of the
    // bodies' box and at most four times it.
    const MagneticExtent extent = magnetic_extent(*cache, model, induced_order, threshold > 0 ? threshold : io::kAutoThresholdFraction * reference);
    region = extent.box;
    const double size = region.isEmpty() ? 0.0 : region.sizes().maxCoeff();
    double margin = std::clamp(extent.reach, 0.25 * size, 4.0 * size);
    if (req.margin) margin = *req.margin;
    else if (!req.margin_auto && field && defaults.margin) margin = *defaults.margin;
    region.min() -= Vec3::Constant(margin);
    region.max() += Vec3::Constant(margin);
  }
  const double voxel = req.voxel.value_or(field && defaults.voxel ? *defaults.voxel : region.sizes().maxCoeff() / 128.0);
  if (!(voxel > 0) || !std::isfinite(voxel)) {
    spdlog::error("the voxel size must be positive");
    return kUsage;
  }
  if (!region.min().allFinite() || !region.max().allFinite() || region.isEmpty()) {
    spdlog::error("the field region is empty or not finite");
    return kUsage;
  }
  // Voxel centres on multiples of the voxel size (frames and split runs share one lattice).
  const Eigen::Vector3d lo = (region.min() / voxel).array().floor() * voxel;
  const Eigen::Vector3d hi = (region.max() / voxel).array().ceil() * voxel;
  // Counts in floating point first: a tiny voxel must be refused, not overflow an int.
  const Eigen::Vector3d counts = ((hi - lo) / voxel).array().round() + 1;
  const double nvox = counts.prod();
  if (!(nvox <= double(req.max_voxels))) {
    spdlog::error("{:.3g} x {:.3g} x {:.3g} voxels ({:.3g}) exceeds the limit of {:.3g}: raise --voxel (now {} m)",
                  counts[0], counts[1], counts[2], nvox, double(req.max_voxels), voxel);
    return kUsage;
  }
  const Eigen::Vector3i dims = counts.cast<int>();
  magnetics::FieldOptions opt;
  opt.theta = req.theta;
  opt.near_field = cache->parameter_doubles("near_field").at(0);
  opt.smear_inside = true;
  opt.single_precision = true;
  opt.surfaces = true;  // the same field as probe and previews (physics.md §12)

  spdlog::info("field volumes: {} x {} x {} voxels of {:.4g} mm over [{:.4g} {:.4g} {:.4g}]-[{:.4g} {:.4g} {:.4g}] m, "
               "frames {}-{} every {}; active where the bodies' |B| >= {:.3g} T, density 1 at {:.3g} T",
               dims[0], dims[1], dims[2], voxel * 1e3, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], a, b, every, threshold,
               reference);
  const auto coms = cache->centers_of_mass();
  magnetics::State st;
  st.resize(model);
  // Every `every`-th frame counted from the shot's first frame (the scene's), whatever the range:
  // chunks of a farm job and a full run write the same frames.
  const FrameSelection pick{a, b, every, cache->first_frame()};
  const int last_wanted = pick.last_wanted();
  Progress progress("field", "field", pick.count(), g.quiet);
  int done = 0;
  std::size_t active_total = 0, voxels_total = 0;
  for (int i = 0; i < cache->frame_count(); ++i) {
    const io::CacheFrame fr = cache->frame(i);
    if (!pick.wanted(fr.frame)) continue;
    if (interrupt_requested()) {
      progress.finish();
      spdlog::warn("interrupted after {} volumes", done);
      return kInterrupted;
    }
    place_frame(model, coms, induced_order, fr, st);  // poses and the stored induced moments
    io::FieldSamples samples;
    samples.origin = lo;
    samples.voxel = voxel;
    samples.dims = dims;
    samples.applied = fr.applied_field;
    evaluate_field_grid(model, st, opt, threshold, samples);
    io::VolumeInfo info;
    info.frame = fr.frame;
    info.time = fr.time;
    info.scene_hash = cache->scene_hash();
    info.scene_name = cache->attribute("scene_name");
    info.threshold = threshold;
    info.reference = reference;
    const std::string path = expand_pattern(pattern, fr.frame);
    try {
      const std::size_t active = io::write_field_volume(path, samples, info);
      spdlog::debug("{}: {} active voxels", path, active);
      active_total += active;
      voxels_total += std::size_t(dims.prod());
    } catch (const std::exception& e) {
      progress.finish();
      spdlog::error("{}", e.what());
      return kFailure;
    }
    ++done;
    progress.update(done, fr.frame, last_wanted);
  }
  progress.finish();
  spdlog::info("wrote {} field volumes ({}), {:.3g}% of their voxels active", done, pattern,
               voxels_total ? 100.0 * double(active_total) / double(voxels_total) : 0.0);
  return kOk;
}

}  // namespace magbake::cli
