// magbake preview: PNG frames of a cache, rendered offscreen (OSMesa), with optional field lines.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "cache_export.h"
#include "field_export.h"
#include "field_lines.h"
#include "gl_context.h"
#include "io/cache.h"
#include "magnetics/system.h"
#include "png_file.h"
#include "preview_export.h"
#include "progress.h"
#include "renderer.h"
#include "shot_geometry.h"

namespace magbake::cli {
namespace fs = std::filesystem;
using magnetics::Vec3;
using render::Vec3f;

namespace {

Eigen::Matrix4f transform(const io::CacheFrame& fr, int b) {
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m.block<3, 3>(0, 0) = fr.orientation[b].normalized().toRotationMatrix().cast<float>();
  m.block<3, 1>(0, 3) = fr.position[b].cast<float>();
  return m;
}

}  // namespace

int export_preview(const std::string& cache_path, const PreviewRequest& req, const Global& g) {
  std::optional<io::CacheReader> cache;
  int a = 0, b = 0;
  if (const int rc = open_cache_range(cache_path, req.frames, cache, a, b); rc != kOk) return rc;
  std::optional<scene::FieldOutput> field_out;
  std::optional<scene::PreviewOutput> scene_preview;
  if (const int rc = stored_outputs(*cache, !req.pattern.empty(), field_out, scene_preview); rc != kOk) return rc;
  const scene::PreviewOutput defaults = scene_preview.value_or(scene::PreviewOutput{});
  const int width = req.width > 0 ? req.width : defaults.width, height = req.height > 0 ? req.height : defaults.height;
  if (width < 16 || height < 16 || width > 8192 || height > 8192) {
    spdlog::error("--size must be between 16x16 and 8192x8192, got {}x{}", width, height);
    return kUsage;
  }
  const bool with_lines = req.field_lines.value_or(defaults.field_lines);
  std::string pattern = !req.pattern.empty() ? req.pattern : (scene_preview ? defaults.path : "");
  if (req.pattern.empty() && !pattern.empty()) {
    if (const int rc = check_scene_output_path(pattern, req.allow_absolute, "outputs.preview.path"); rc != kOk) return rc;
  }
  if (pattern.empty()) {
    pattern = (fs::path(cache_path).parent_path() / (fs::path(cache_path).stem().string() + ".preview.####.png")).string();
  }
  if (const int rc = prepare_output_folder(pattern, a, "previews"); rc != kOk) return rc;
  // Every `every`-th frame counted from the shot's first frame, whatever the range (as field).
  const FrameSelection pick{a, b, std::max(1, req.every.value_or(1)), cache->first_frame()};

  // Geometry and a steady camera: every body's extent over the whole shot.
  const ShotGeometry geo = load_geometry(*cache);
  std::vector<io::CacheFrame> frames;
  for (int i = 0; i < cache->frame_count(); ++i) frames.push_back(cache->frame(i));
  const magnetics::Box3 box = shot_box(geo, frames);
  render::View view;
  if (defaults.camera && req.auto_camera == false) {
    view.eye = defaults.camera->position;
    view.target = defaults.camera->look_at;
    view.fov = defaults.camera->fov;
  } else {
    // Auto-framing: a three-quarter view from above, as close as it can be while every corner
    // of the shot's box stays inside the picture with a 6% border.
    const Vec3 c = box.center();
    view.fov = 40.0 * std::numbers::pi / 180.0;
    const double tan_v = 0.94 * std::tan(0.5 * view.fov), tan_h = tan_v * double(width) / height;
    const Vec3 back = Vec3(1.0, -1.6, 0.9).normalized();  // from the target towards the eye
    const Vec3 right = Vec3::UnitZ().cross(back).normalized(), up = back.cross(right);
    double dist = 1e-3;
    for (int k = 0; k < 8; ++k) {
      const Vec3 p = Vec3(k & 1 ? box.max()[0] : box.min()[0], k & 2 ? box.max()[1] : box.min()[1],
                          k & 4 ? box.max()[2] : box.min()[2]) - c;
      const double z = p.dot(back);
      dist = std::max({dist, z + std::abs(p.dot(right)) / tan_h, z + std::abs(p.dot(up)) / tan_v});
    }
    view.target = c;
    view.eye = c + back * dist;
  }
  const double dist = (view.eye - view.target).norm();
  view.near_plane = std::max(1e-4, 0.01 * dist);
  view.far_plane = 20 * dist + box.sizes().norm();

  std::unique_ptr<render::GlContext> ctx;
  std::unique_ptr<render::Renderer> renderer;
  try {
    ctx = render::GlContext::create_offscreen(width, height, g.threads);
    renderer = std::make_unique<render::Renderer>(*ctx);
  } catch (const std::exception& e) {
    spdlog::error("cannot start offscreen rendering: {}", e.what());
    return kFailure;
  }
  renderer->set_meshes(geo.meshes);
  {
    // Ground grid under everything: lines every 1, 2 or 5 x 10^k, about ten across.
    const double extent = 0.75 * std::max(box.sizes()[0], box.sizes()[1]) + 0.25 * box.sizes().norm();
    const double raw = extent / 5.0, p = std::pow(10.0, std::floor(std::log10(raw)));
    const double spacing = raw / p < 2 ? p : raw / p < 5 ? 2 * p : 5 * p;
    renderer->set_ground(box.center()[0], box.center()[1], box.min()[2] - 1e-4 * box.sizes().norm(), extent, spacing);
  }

  // Field lines need the magnetic model (rebuilt from the cache).
  std::vector<int> induced_order;
  magnetics::Model model;
  magnetics::State st;
  const auto coms = cache->centers_of_mass();
  if (with_lines) {
    model = cache->model(&induced_order);
    st.resize(model);
  }
  const magnetics::Box3 line_bounds = field_line_region(box);

  // Contact sheet: frames tiled in rows, box-filtered down so the sheet is at most 1920 pixels
  // wide; each frame is added as it is drawn (memory: one sheet, not every frame).
  int n_sheet = 0;
  for (const io::CacheFrame& fr : frames) n_sheet += pick.wanted(fr.frame);
  const int cols = static_cast<int>(std::ceil(std::sqrt(double(n_sheet))));
  const int rows = (n_sheet + cols - 1) / cols;
  const int step = std::max(1, (cols * width + 1919) / 1920);
  const int tw = width / step, th = height / step;
  std::vector<std::uint8_t> sheet;
  if (!req.contact_sheet.empty()) sheet.assign(std::size_t(cols * tw) * rows * th * 4, 255);
  auto add_to_sheet = [&](const std::vector<std::uint8_t>& rgba, int i) {
    const int ox = (i % cols) * tw, oy = (i / cols) * th;
    for (int y = 0; y < th; ++y) {
      for (int x = 0; x < tw; ++x) {
        int sum[4] = {0, 0, 0, 0};
        for (int yy = 0; yy < step; ++yy) {
          for (int xx = 0; xx < step; ++xx) {
            const std::size_t s = (std::size_t(y * step + yy) * width + x * step + xx) * 4;
            for (int k = 0; k < 4; ++k) sum[k] += rgba[s + k];
          }
        }
        const std::size_t d = (std::size_t(oy + y) * cols * tw + ox + x) * 4;
        for (int k = 0; k < 4; ++k) sheet[d + k] = static_cast<std::uint8_t>((sum[k] + step * step / 2) / (step * step));
      }
    }
  };
  const int last_wanted = pick.last_wanted();
  Progress progress("preview", "preview", pick.count(), g.quiet);
  int done = 0;
  for (const io::CacheFrame& fr : frames) {
    if (!pick.wanted(fr.frame)) continue;
    if (interrupt_requested()) {
      progress.finish();
      spdlog::warn("interrupted after {} previews", done);
      return kInterrupted;
    }
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    std::vector<Eigen::Matrix4f> xf;
    for (std::size_t bi = 0; bi < geo.body_points.size(); ++bi) xf.push_back(transform(fr, int(bi)));
    std::vector<render::Polyline> lines;
    if (with_lines && !model.empty()) {
      place_frame(model, coms, induced_order, fr, st);
      lines = trace_field_lines(model, st, fr.applied_field, line_bounds);
    }
    const auto t1 = Clock::now();
    const std::vector<std::uint8_t> rgba = renderer->draw(view, xf, lines);
    const auto t2 = Clock::now();
    const std::string path = expand_pattern(pattern, fr.frame);
    try {
      render::write_png(path, rgba, width, height);
    } catch (const std::exception& e) {
      progress.finish();
      spdlog::error("{}", e.what());
      return kFailure;
    }
    const auto t3 = Clock::now();
    if (!sheet.empty()) add_to_sheet(rgba, done);
    // One machine-readable line per frame for bench/run_preview_bench.sh (shown with -v).
    auto ms = [](Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); };
    spdlog::debug("preview frame {} ms: lines {:.2f} draw {:.2f} png {:.2f} total {:.2f} ({} lines)", fr.frame, ms(t1 - t0),
                  ms(t2 - t1), ms(t3 - t2), ms(Clock::now() - t0), lines.size());
    ++done;
    progress.update(done, fr.frame, last_wanted);
  }
  progress.finish();
  if (!sheet.empty()) {
    try {
      render::write_png(req.contact_sheet, sheet, cols * tw, rows * th);
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return kFailure;
    }
  }
  spdlog::info("wrote {} previews ({}x{}, {})", done, width, height, pattern);
  return kOk;
}

}  // namespace magbake::cli
