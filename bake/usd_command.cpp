// magbake export --usd: a bake as a USD stage (text, USDA 1.0), for DCCs and renderers that read
// no HDF5 (docs/usd.md). Written by hand in the documented text format: no USD library is
// packaged here; tests open the result with the reference implementation (PyPI's usd-core).
#include <spdlog/spdlog.h>

#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "cache_export.h"
#include "cli.h"
#include "field_lines.h"
#include "io/cache.h"
#include "progress.h"
#include "scene/frame_pattern.h"
#include "shot_geometry.h"
#include "usd_layer.h"

namespace magbake::cli {
namespace fs = std::filesystem;
using magnetics::Mat3;
using magnetics::Quat;
using magnetics::Vec3;

namespace {

// A valid USD prim name ([A-Za-z_][A-Za-z0-9_]*) for `name`, not yet in `used`.
std::string prim_name(const std::string& name, std::set<std::string>& used) {
  std::string s;
  for (char c : name) s += (std::isalnum(static_cast<unsigned char>(c)) || c == '_') ? c : '_';
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) s.insert(s.begin(), '_');
  std::string out = s;
  for (int k = 2; used.count(out); ++k) out = fmt::format("{}_{}", s, k);
  used.insert(out);
  return out;
}

// An asset path relative to the layer's folder when that is possible (without the @ quotes).
std::string asset(const fs::path& file, const fs::path& layer_dir) {
  std::error_code ec;
  const fs::path rel = fs::relative(fs::absolute(file), fs::absolute(layer_dir), ec);
  const std::string p = (ec || rel.empty()) ? fs::absolute(file).string() : fmt::format("./{}", rel.string());
  return p;
}

}  // namespace

int cmd_export_usd(const std::string& cache_path, const UsdRequest& req, const Global& g) {
  const fs::path stage_path(req.usd);
  const std::string ext = stage_path.extension().string();
  if (ext != ".usda" && ext != ".usdc" && ext != ".usd") {
    spdlog::error("--usd {}: the stage's name must end in .usda (text), .usdc or .usd (binary crate)", req.usd);
    return kUsage;
  }
  const bool binary = ext != ".usda";
  std::optional<io::CacheReader> cache;
  int a = 0, b = 0;
  if (const int rc = open_cache_range(cache_path, req.frames, cache, a, b); rc != kOk) return rc;
  std::optional<scene::FieldOutput> field_out;
  std::optional<scene::PreviewOutput> preview_out;
  (void)stored_outputs(*cache, true, field_out, preview_out);  // a bad stored pattern: no volume, warned

  // Field volumes: --field PATTERN, else outputs.field.path's file name beside the cache, if its
  // files are there; "none" = no volume.
  std::string field_pattern = req.field_pattern;
  if (field_pattern.empty() && field_out) {
    field_pattern = (fs::path(cache_path).parent_path() / fs::path(field_out->path).filename()).string();
  }
  if (field_pattern == "none") field_pattern.clear();
  if (!field_pattern.empty()) {
    if (const auto e = scene::frame_pattern_error(field_pattern)) {
      spdlog::error("--field {}: {}", field_pattern, *e);
      return kUsage;
    }
  }

  const ShotGeometry geo = load_geometry(*cache);
  const std::vector<io::CacheReader::BodyInfo> info = cache->body_info();
  const std::vector<std::string>& names = cache->body_names();
  const std::size_t n = names.size();
  std::vector<int> induced_order;
  const magnetics::Model model = cache->model(&induced_order);
  const bool magnetic_any = model.cell_count() > 0;

  std::vector<io::CacheFrame> frames;
  for (int i = 0; i < cache->frame_count(); ++i) {
    io::CacheFrame fr = cache->frame(i);
    if (fr.frame >= a && fr.frame <= b) frames.push_back(std::move(fr));
  }

  // The stage as a layer (bake/usd_layer.h), written as USDA or USDC below.
  usd::Layer layer;
  std::set<std::string> used;
  const std::string shot = prim_name(fs::path(cache_path).stem().string(), used);
  layer.default_prim = shot;
  layer.doc = "magbake bake " + fs::path(cache_path).filename().string() + ", frames " + std::to_string(a) + "-" +
              std::to_string(b) + " (magbake export --usd)";
  layer.start = a, layer.end = b, layer.fps = cache->fps();
  usd::Prim root{shot, "Xform", "assembly"};
  usd::Prim bodies{"bodies", "Scope"};
  auto v3 = [](const Vec3& v) { return usd::Vec3d{v[0], v[1], v[2]}; };
  auto v3f = [](const render::Vec3f& v) { return usd::Vec3f{v[0], v[1], v[2]}; };
  auto sampled = [&](const std::string& name, const std::string& type, bool custom, auto value_at) {
    usd::Attribute at{name, type, custom};
    for (const io::CacheFrame& fr : frames) at.samples.emplace_back(double(fr.frame), value_at(fr));
    return at;
  };
  // Each body's total moment per frame (world): permanent cells turned with it plus induced.
  std::vector<std::vector<Vec3>> moments;
  if (magnetic_any) {
    const std::vector<Vec3> permanent = body_permanent_moments(model);
    for (const io::CacheFrame& fr : frames) moments.push_back(body_moments(model, permanent, induced_order, fr));
  }
  std::set<std::string> body_used;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string prim = prim_name(names[i], body_used);
    usd::Prim body{prim, "Xform"};
    body.custom_data = {{"magbake_name", names[i]}};
    // Body origin (the scene's shape origin, world frame) and orientation, as the cache stores
    // them: transforming the body-frame meshes below with them puts them where the bake had them.
    body.attributes.push_back(
        sampled("xformOp:translate", "double3", false, [&](const io::CacheFrame& fr) { return usd::Value(v3(fr.position[i])); }));
    body.attributes.push_back(sampled("xformOp:orient", "quatd", false, [&](const io::CacheFrame& fr) {
      const Quat q = fr.orientation[i].normalized();
      return usd::Value(usd::Quatd{q.w(), q.x(), q.y(), q.z()});
    }));
    usd::Attribute order{"xformOpOrder", "token[]"};
    order.uniform = true;
    order.value = std::vector<usd::Token>{{"xformOp:translate"}, {"xformOp:orient"}};
    body.attributes.push_back(order);
    body.attributes.push_back({"magbake:mass", "double", true, false, usd::Value(i < info.size() ? info[i].mass : 0.0)});
    body.attributes.push_back({"magbake:material", "string", true, false, usd::Value(i < info.size() ? info[i].material : "")});
    body.attributes.push_back({"magbake:motion", "string", true, false, usd::Value(i < info.size() ? info[i].motion : "")});
    body.attributes.push_back(
        sampled("magbake:magneticForce", "double3", true, [&](const io::CacheFrame& fr) { return usd::Value(v3(fr.force[i])); }));
    if (magnetic_any) {
      // Total magnetic moment, world frame: the permanent cells turned with the body plus the
      // induced moments of its cells.
      usd::Attribute moment{"magbake:magneticMoment", "double3", true};
      for (std::size_t k = 0; k < frames.size(); ++k) moment.samples.emplace_back(double(frames[k].frame), usd::Value(v3(moments[k][i])));
      body.attributes.push_back(std::move(moment));
    }
    // Render meshes (as the previews draw them), body frame, one colour per triangle.
    // A body of one mesh names it after itself (Blender's import merges such an Xform and its
    // mesh into one object of that name); a body with parts has <body>_geometry, _geometry_1, ...
    int meshes_of_body = 0, part = 0;
    for (const render::Mesh& mesh : geo.meshes) meshes_of_body += mesh.body == static_cast<int>(i) && !mesh.positions.empty();
    for (const render::Mesh& mesh : geo.meshes) {
      if (mesh.body != static_cast<int>(i) || mesh.positions.empty()) continue;
      const std::string mesh_name = meshes_of_body == 1 ? prim
                                    : part == 0         ? fmt::format("{}_geometry", prim)
                                                        : fmt::format("{}_geometry_{}", prim, part);
      ++part;
      const std::size_t nt = mesh.positions.size() / 3;
      render::Vec3f lo = mesh.positions[0], hi = mesh.positions[0];
      for (const auto& p : mesh.positions) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
      usd::Prim m{mesh_name, "Mesh"};
      m.attributes.push_back({"extent", "float3[]", false, false, usd::Value(std::vector<usd::Vec3f>{v3f(lo), v3f(hi)})});
      m.attributes.push_back({"faceVertexCounts", "int[]", false, false, usd::Value(std::vector<int>(nt, 3))});
      std::vector<int> indices(3 * nt);
      for (std::size_t v = 0; v < 3 * nt; ++v) indices[v] = static_cast<int>(v);
      m.attributes.push_back({"faceVertexIndices", "int[]", false, false, usd::Value(std::move(indices))});
      std::vector<usd::Vec3f> points, colors;
      for (std::size_t v = 0; v < 3 * nt; ++v) points.push_back(v3f(mesh.positions[v]));
      for (std::size_t t = 0; t < nt; ++t) colors.push_back(v3f(mesh.colors[3 * t]));
      m.attributes.push_back({"points", "point3f[]", false, false, usd::Value(std::move(points))});
      usd::Attribute color{"primvars:displayColor", "color3f[]", false, false, usd::Value(std::move(colors))};
      color.interpolation = "uniform";
      m.attributes.push_back(std::move(color));
      if (mesh.alpha < 1.0f) {
        usd::Attribute opacity{"primvars:displayOpacity", "float[]", false, false, usd::Value(std::vector<float>{mesh.alpha})};
        opacity.interpolation = "constant";
        m.attributes.push_back(std::move(opacity));
      }
      usd::Attribute scheme{"subdivisionScheme", "token", false, true, usd::Value(usd::Token{"none"})};
      m.attributes.push_back(std::move(scheme));
      body.children.push_back(std::move(m));
    }
    bodies.children.push_back(std::move(body));
  }
  root.children.push_back(std::move(bodies));

  // Field volumes: one Volume whose two OpenVDB fields point at the frame's file.
  int volumes = 0;
  if (!field_pattern.empty()) {
    std::vector<std::pair<int, std::string>> files;
    for (const io::CacheFrame& fr : frames) {
      const fs::path file = expand_pattern(field_pattern, fr.frame);
      if (fs::exists(file)) files.emplace_back(fr.frame, asset(file, stage_path.parent_path().empty() ? fs::path(".") : stage_path.parent_path()));
    }
    if (files.empty()) {
      spdlog::warn("no field volume {} found for frames {}-{}: the stage has no Volume ({} writes them)", field_pattern, a,
                   b, "magbake field");
    } else {
      volumes = static_cast<int>(files.size());
      usd::Prim volume{"field", "Volume"};
      volume.relationships.push_back({"field:B", {fmt::format("/{}/field/B", shot)}});
      volume.relationships.push_back({"field:density", {fmt::format("/{}/field/density", shot)}});
      for (const char* grid : {"B", "density"}) {
        usd::Prim g{grid, "OpenVDBAsset"};
        g.attributes.push_back({"fieldDataType", "token", false, false, usd::Value(usd::Token{grid[0] == 'B' ? "float3" : "float"})});
        g.attributes.push_back({"fieldName", "token", false, false, usd::Value(usd::Token{grid})});
        usd::Attribute path{"filePath", "asset"};
        for (const auto& [frame, file] : files) path.samples.emplace_back(double(frame), usd::Value(usd::Asset{file}));
        g.attributes.push_back(std::move(path));
        volume.children.push_back(std::move(g));
      }
      root.children.push_back(std::move(volume));
    }
  }

  // Field lines: the previews' streamlines, one time sample per frame (their number and length
  // change from frame to frame, so the topology is time-sampled too).
  std::size_t line_points = 0;
  if (req.field_lines && magnetic_any) {
    const magnetics::Box3 region = field_line_region(shot_box(geo, frames));
    const std::vector<Vec3> coms = cache->centers_of_mass();
    magnetics::State st;
    st.resize(model);
    usd::Attribute counts{"curveVertexCounts", "int[]"}, points{"points", "point3f[]"}, colors{"primvars:displayColor", "color3f[]"},
        extents{"extent", "float3[]"};
    colors.interpolation = "vertex";
    Progress progress("usd", "field lines", static_cast<int>(frames.size()), g.quiet);
    int done = 0;
    for (const io::CacheFrame& fr : frames) {
      if (interrupt_requested()) {
        progress.finish();
        spdlog::warn("interrupted: {} not written", req.usd);
        return kInterrupted;
      }
      place_frame(model, coms, induced_order, fr, st);
      const std::vector<render::Polyline> lines = trace_field_lines(model, st, fr.applied_field, region);
      render::Vec3f lo = render::Vec3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
      std::vector<int> n_of;
      std::vector<usd::Vec3f> p, c;
      for (const render::Polyline& line : lines) {
        n_of.push_back(static_cast<int>(line.points.size()));
        for (std::size_t k = 0; k < line.points.size(); ++k) {
          lo = lo.cwiseMin(line.points[k]), hi = hi.cwiseMax(line.points[k]);
          p.push_back(v3f(line.points[k]));
          c.push_back(v3f(line.colors[k]));
        }
      }
      if (lines.empty()) lo = hi = render::Vec3f::Zero();
      line_points += p.size();
      const double t = fr.frame;
      counts.samples.emplace_back(t, usd::Value(std::move(n_of)));
      points.samples.emplace_back(t, usd::Value(std::move(p)));
      colors.samples.emplace_back(t, usd::Value(std::move(c)));
      extents.samples.emplace_back(t, usd::Value(std::vector<usd::Vec3f>{v3f(lo), v3f(hi)}));
      progress.update(++done, fr.frame, b);
    }
    progress.finish();
    usd::Prim curves{"field_lines", "BasisCurves"};
    curves.doc = "streamlines of B as magbake preview draws them, coloured by log |B| (violet 10 uT, teal 1 mT, yellow 1 T)";
    curves.attributes.push_back({"type", "token", false, true, usd::Value(usd::Token{"linear"})});
    curves.attributes.push_back({"wrap", "token", false, true, usd::Value(usd::Token{"nonperiodic"})});
    curves.attributes.push_back(std::move(counts));
    curves.attributes.push_back(std::move(points));
    curves.attributes.push_back(std::move(extents));
    curves.attributes.push_back(std::move(colors));
    usd::Attribute widths{"widths", "float[]", false, false, usd::Value(std::vector<float>{float(0.002 * region.sizes().maxCoeff())})};
    widths.interpolation = "constant";
    curves.attributes.push_back(std::move(widths));
    root.children.push_back(std::move(curves));
  } else if (req.field_lines) {
    spdlog::warn("no magnetic body: no field lines");
  }
  layer.prims.push_back(std::move(root));

  std::error_code ec;
  if (!stage_path.parent_path().empty()) fs::create_directories(stage_path.parent_path(), ec);
  const fs::path tmp = fs::path(req.usd + ".partial");
  {
    std::ofstream out(tmp, std::ios::binary);
    if (binary) {
      const std::vector<char> bytes = usd::to_usdc(layer);
      out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    } else {
      out << usd::to_usda(layer);
    }
    out.close();
    if (!out) {
      spdlog::error("cannot write {}", tmp.string());
      fs::remove(tmp, ec);
      return kFailure;
    }
  }
  fs::rename(tmp, stage_path, ec);
  if (ec) {
    spdlog::error("cannot move {} to {}: {}", tmp.string(), req.usd, ec.message());
    return kFailure;
  }
  if (!g.quiet) {
    spdlog::info("wrote {}: {} bodies, frames {}-{}{}{}", req.usd, n, a, b,
                 volumes > 0 ? fmt::format(", field volumes of {} frames", volumes) : std::string(),
                 req.field_lines && magnetic_any ? fmt::format(", field lines ({} points)", line_points) : std::string());
  }
  return kOk;
}

}  // namespace magbake::cli
