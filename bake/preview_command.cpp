// magbake preview: PNG frames of a cache, rendered offscreen (OSMesa), with optional field lines.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "cache_export.h"
#include "field_export.h"
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

// |B| -> colour for field lines: a log scale from deep violet (10 µT) through teal to yellow (1 T),
// distinct from every material colour.
Vec3f field_color(double b) {
  const double t = std::clamp((std::log10(std::max(b, 1e-12)) + 5.0) / 5.0, 0.0, 1.0);
  const Vec3f a(0.35f, 0.05f, 0.55f), m(0.0f, 0.62f, 0.58f), c(1.0f, 0.86f, 0.0f);
  return t < 0.5 ? Vec3f(a + (m - a) * float(2 * t)) : Vec3f(m + (c - m) * float(2 * t - 1));
}

Eigen::Matrix4f transform(const io::CacheFrame& fr, int b) {
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m.block<3, 3>(0, 0) = fr.orientation[b].normalized().toRotationMatrix().cast<float>();
  m.block<3, 1>(0, 3) = fr.position[b].cast<float>();
  return m;
}

// Streamlines of B (RK4 on the unit direction field) from seeds around each magnet: 20 seeds per
// magnetized body, each traced both ways. A crowded shot (more than kLineSeedBudget / 20 magnetized
// bodies) gets fewer seeds per body (kLineSeedBudget in all, at least 4 each), and its lines end
// where they enter a magnet's bounding sphere instead of running on through chains of magnets:
// the picture stays readable and the tracing cost bounded.
constexpr int kLineSeedBudget = 320;

std::vector<render::Polyline> field_lines(const magnetics::Model& model, const magnetics::State& st,
                                          const Vec3& applied, const magnetics::Box3& bounds) {
  magnetics::Settings fs;
  fs.theta = 0.4;
  fs.near_field = 0.0;
  fs.external_field = applied;
  struct Line {
    std::vector<Vec3> pts;
    std::vector<double> mag;
    double sign;
    bool alive = true;
    bool was_outside = false;  // has been outside every magnet (seeds can start inside one's sphere)
  };
  struct Sphere {
    Vec3 c;
    double r;
  };
  // Seeds around each magnetized body (its root node's sphere); lines end in the bounding
  // sphere of any permanent part (a toy magnet's inserts, not its whole rod).
  std::vector<Sphere> seeds, parts;
  for (int b = 0; b < model.body_count; ++b) {
    if (!model.body_permanent[b] || model.body_root[b] < 0) continue;
    const int root = model.body_root[b];
    seeds.push_back({st.body_pose[b].position + st.node_offset[root], model.node_radius[root]});
  }
  {
    const int np = static_cast<int>(model.part_body.size());
    std::vector<Vec3> sum(np, Vec3::Zero());
    std::vector<int> count(np, 0);
    std::vector<double> reach(np, 0.0);
    for (int c = 0; c < model.cell_count(); ++c) sum[model.cell_part[c]] += model.cell_center[c], ++count[model.cell_part[c]];
    for (int p = 0; p < np; ++p) sum[p] /= std::max(count[p], 1);
    for (int c = 0; c < model.cell_count(); ++c) {
      const int p = model.cell_part[c];
      reach[p] = std::max(reach[p], (model.cell_center[c] - sum[p]).norm() + model.cell_reach[c]);
    }
    for (int p = 0; p < np; ++p) {
      if (count[p] == 0 || model.part_magnetization[p].squaredNorm() == 0) continue;
      parts.push_back({st.body_pose[model.part_body[p]].apply(sum[p]), reach[p]});
    }
  }
  std::vector<Line> lines;
  const double size = bounds.sizes().maxCoeff();
  const bool crowded = int(seeds.size()) * 20 > kLineSeedBudget;
  const int n = std::clamp(kLineSeedBudget / std::max<int>(1, int(seeds.size())), 4, 20);
  for (const Sphere& m : seeds) {
    for (int i = 0; i < n; ++i) {  // seeds on a Fibonacci sphere, each traced both ways
      const double z = 1 - 2 * (i + 0.5) / n, phi = i * std::numbers::pi * (3 - std::sqrt(5.0));
      const Vec3 d(std::sqrt(1 - z * z) * std::cos(phi), std::sqrt(1 - z * z) * std::sin(phi), z);
      for (double sign : {1.0, -1.0}) lines.push_back({{m.c + 1.05 * m.r * d}, {}, sign});
    }
  }
  auto inside_a_magnet = [&](const Vec3& x) {
    for (const Sphere& m : parts) {
      if ((x - m.c).squaredNorm() < m.r * m.r) return true;
    }
    return false;
  };
  const double h = 0.012 * size;
  auto eval = [&](const std::vector<Vec3>& p) {
    return magnetics::field_at_points(model, fs, st, std::span<const Vec3>(p.data(), p.size()));
  };
  for (int step = 0; step < 220; ++step) {
    std::vector<int> live;
    std::vector<Vec3> x;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      if (lines[i].alive) live.push_back(int(i)), x.push_back(lines[i].pts.back());
    }
    if (live.empty()) break;
    auto dir = [&](const std::vector<Vec3>& B, std::size_t k) {
      const double n = B[k].norm();
      return n > 0 ? Vec3(lines[live[k]].sign * B[k] / n) : Vec3(Vec3::Zero());
    };
    const std::vector<Vec3> B1 = eval(x);
    std::vector<Vec3> x2(x.size()), x3(x.size()), x4(x.size());
    for (std::size_t k = 0; k < x.size(); ++k) x2[k] = x[k] + 0.5 * h * dir(B1, k);
    const std::vector<Vec3> B2 = eval(x2);
    for (std::size_t k = 0; k < x.size(); ++k) x3[k] = x[k] + 0.5 * h * dir(B2, k);
    const std::vector<Vec3> B3 = eval(x3);
    for (std::size_t k = 0; k < x.size(); ++k) x4[k] = x[k] + h * dir(B3, k);
    const std::vector<Vec3> B4 = eval(x4);
    for (std::size_t k = 0; k < x.size(); ++k) {
      Line& l = lines[live[k]];
      l.mag.push_back(B1[k].norm());
      const Vec3 next = x[k] + h / 6.0 * (dir(B1, k) + 2 * dir(B2, k) + 2 * dir(B3, k) + dir(B4, k));
      const bool in_magnet = crowded && inside_a_magnet(next);
      const bool ends_in_magnet = crowded && in_magnet && (l.was_outside || l.pts.size() > 10);
      l.was_outside = l.was_outside || !in_magnet;
      if (B1[k].norm() < 1e-5 || !bounds.contains(next) || !next.allFinite() || ends_in_magnet) {
        if (next.allFinite() && bounds.contains(next)) l.pts.push_back(next), l.mag.push_back(B1[k].norm());
        l.alive = false;
        continue;
      }
      l.pts.push_back(next);
    }
  }
  std::vector<render::Polyline> out;
  for (const Line& l : lines) {
    if (l.pts.size() < 3) continue;
    render::Polyline p;
    for (std::size_t k = 0; k < l.pts.size(); ++k) {
      p.points.push_back(l.pts[k].cast<float>());
      p.colors.push_back(field_color(l.mag[std::min(k, l.mag.size() - 1)]));
    }
    out.push_back(std::move(p));
  }
  return out;
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
  magnetics::Box3 box;
  for (const io::CacheFrame& fr : frames) {
    for (std::size_t bi = 0; bi < geo.body_points.size(); ++bi) {
      for (const Vec3& p : geo.body_points[bi]) box.extend(fr.position[bi] + fr.orientation[bi] * p);
    }
  }
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
  const std::vector<double> ext = cache->parameter_doubles("external_field");
  const Vec3 applied(ext.at(0), ext.at(1), ext.at(2));
  if (with_lines) {
    model = cache->model(&induced_order);
    st.resize(model);
  }
  // Field lines are traced inside a cube around the shot (flat shots still get their loops).
  const double line_half = std::max(box.sizes().maxCoeff(), 1e-3);
  const magnetics::Box3 line_bounds(box.center() - Vec3::Constant(line_half), box.center() + Vec3::Constant(line_half));

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
      for (int bi = 0; bi < model.body_count; ++bi) {
        st.body_pose[bi] = magnetics::Pose{fr.orientation[bi], fr.position[bi] + fr.orientation[bi] * coms[bi]};
      }
      std::vector<Vec3> induced(model.induced_cells.size());
      for (std::size_t k = 0; k < induced.size(); ++k) induced[k] = fr.induced_moment.at(induced_order[k]);
      magnetics::place(model, st, induced);
      lines = field_lines(model, st, applied, line_bounds);
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
