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

// A USDA string literal.
std::string quoted(const std::string& s) {
  std::string out(1, '"');
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  out.push_back('"');
  return out;
}

// Doubles round-trip exactly with 17 significant digits.
std::string d(double v) { return fmt::format("{:.17g}", v); }
std::string f(float v) { return fmt::format("{:.9g}", v); }
std::string vec(const Vec3& v) { return fmt::format("({:.17g}, {:.17g}, {:.17g})", v[0], v[1], v[2]); }
std::string vecf(const render::Vec3f& v) { return fmt::format("({:.9g}, {:.9g}, {:.9g})", v[0], v[1], v[2]); }

// An asset path relative to the layer's folder when that is possible.
std::string asset(const fs::path& file, const fs::path& layer_dir) {
  std::error_code ec;
  const fs::path rel = fs::relative(fs::absolute(file), fs::absolute(layer_dir), ec);
  const std::string p = (ec || rel.empty()) ? fs::absolute(file).string() : fmt::format("./{}", rel.string());
  return fmt::format("@{}@", p);
}

}  // namespace

int cmd_export_usd(const std::string& cache_path, const UsdRequest& req, const Global& g) {
  const fs::path usd(req.usd);
  if (usd.extension() != ".usda") {
    spdlog::error("--usd {}: magbake writes USD as text (.usda); convert it with `usdcat {} -o shot.usdc` if you need "
                  "the binary form",
                  req.usd, usd.filename().replace_extension(".usda").string());
    return kUsage;
  }
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
  // Permanent moment of each body in its frame (A·m²), and which body each induced cell is on.
  std::vector<Vec3> permanent(n, Vec3::Zero());
  for (int c = 0; c < model.cell_count(); ++c) {
    if (model.cell_body[c] >= 0 && static_cast<std::size_t>(model.cell_body[c]) < n) permanent[model.cell_body[c]] += model.cell_moment[c];
  }
  const bool magnetic_any = model.cell_count() > 0;

  std::vector<io::CacheFrame> frames;
  for (int i = 0; i < cache->frame_count(); ++i) {
    io::CacheFrame fr = cache->frame(i);
    if (fr.frame >= a && fr.frame <= b) frames.push_back(std::move(fr));
  }

  std::ostringstream o;
  std::set<std::string> used;
  const std::string shot = prim_name(fs::path(cache_path).stem().string(), used);
  o << "#usda 1.0\n(\n";
  o << "    defaultPrim = " << quoted(shot) << "\n";
  o << "    doc = " << quoted("magbake bake " + fs::path(cache_path).filename().string() + ", frames " + std::to_string(a) +
                             "-" + std::to_string(b) + " (magbake export --usd)")
    << "\n";
  o << "    endTimeCode = " << b << "\n";
  o << "    framesPerSecond = " << d(cache->fps()) << "\n";
  o << "    metersPerUnit = 1\n";
  o << "    startTimeCode = " << a << "\n";
  o << "    timeCodesPerSecond = " << d(cache->fps()) << "\n";
  o << "    upAxis = \"Z\"\n)\n\n";
  o << "def Xform " << quoted(shot) << " (\n    kind = \"assembly\"\n)\n{\n";
  o << "    def Scope \"bodies\"\n    {\n";
  std::set<std::string> body_used;
  for (std::size_t i = 0; i < n; ++i) {
    const std::string prim = prim_name(names[i], body_used);
    o << "        def Xform " << quoted(prim) << " (\n            customData = {\n                string magbake_name = "
      << quoted(names[i]) << "\n            }\n        )\n        {\n";
    // Body origin (the scene's shape origin, world frame) and orientation, as the cache stores
    // them: transforming the body-frame meshes below with them puts them where the bake had them.
    o << "            double3 xformOp:translate.timeSamples = {\n";
    for (const io::CacheFrame& fr : frames) o << "                " << fr.frame << ": " << vec(fr.position[i]) << ",\n";
    o << "            }\n            quatd xformOp:orient.timeSamples = {\n";
    for (const io::CacheFrame& fr : frames) {
      const Quat q = fr.orientation[i].normalized();
      o << "                " << fr.frame << ": (" << d(q.w()) << ", " << d(q.x()) << ", " << d(q.y()) << ", " << d(q.z())
        << "),\n";
    }
    o << "            }\n            uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]\n";
    o << "            custom double magbake:mass = " << d(i < info.size() ? info[i].mass : 0.0) << "\n";
    o << "            custom string magbake:material = " << quoted(i < info.size() ? info[i].material : "") << "\n";
    o << "            custom string magbake:motion = " << quoted(i < info.size() ? info[i].motion : "") << "\n";
    o << "            custom double3 magbake:magneticForce.timeSamples = {\n";
    for (const io::CacheFrame& fr : frames) o << "                " << fr.frame << ": " << vec(fr.force[i]) << ",\n";
    o << "            }\n";
    if (magnetic_any) {
      // Total magnetic moment, world frame: the permanent cells turned with the body plus the
      // induced moments of its cells.
      o << "            custom double3 magbake:magneticMoment.timeSamples = {\n";
      for (const io::CacheFrame& fr : frames) {
        Vec3 m = fr.orientation[i].normalized() * permanent[i];
        for (std::size_t k = 0; k < model.induced_cells.size() && k < induced_order.size(); ++k) {
          const int c = model.induced_cells[k];
          const std::size_t r = static_cast<std::size_t>(induced_order[k]);
          if (static_cast<std::size_t>(model.cell_body[c]) == i && r < fr.induced_moment.size()) m += fr.induced_moment[r];
        }
        o << "                " << fr.frame << ": " << vec(m) << ",\n";
      }
      o << "            }\n";
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
      o << "            def Mesh " << quoted(mesh_name) << "\n            {\n";
      o << "                float3[] extent = [" << vecf(lo) << ", " << vecf(hi) << "]\n";
      o << "                int[] faceVertexCounts = [";
      for (std::size_t t = 0; t < nt; ++t) o << (t ? ", 3" : "3");
      o << "]\n                int[] faceVertexIndices = [";
      for (std::size_t v = 0; v < 3 * nt; ++v) o << (v ? ", " : "") << v;
      o << "]\n                point3f[] points = [";
      for (std::size_t v = 0; v < 3 * nt; ++v) o << (v ? ", " : "") << vecf(mesh.positions[v]);
      o << "]\n                color3f[] primvars:displayColor = [";
      for (std::size_t t = 0; t < nt; ++t) o << (t ? ", " : "") << vecf(mesh.colors[3 * t]);
      o << "] (\n                    interpolation = \"uniform\"\n                )\n";
      if (mesh.alpha < 1.0f) {
        o << "                float[] primvars:displayOpacity = [" << f(mesh.alpha)
          << "] (\n                    interpolation = \"constant\"\n                )\n";
      }
      o << "                uniform token subdivisionScheme = \"none\"\n            }\n";
    }
    o << "        }\n";
  }
  o << "    }\n";

  // Field volumes: one Volume whose two OpenVDB fields point at the frame's file.
  int volumes = 0;
  if (!field_pattern.empty()) {
    std::vector<std::pair<int, std::string>> files;
    for (const io::CacheFrame& fr : frames) {
      const fs::path file = expand_pattern(field_pattern, fr.frame);
      if (fs::exists(file)) files.emplace_back(fr.frame, asset(file, usd.parent_path().empty() ? fs::path(".") : usd.parent_path()));
    }
    if (files.empty()) {
      spdlog::warn("no field volume {} found for frames {}-{}: the stage has no Volume ({} writes them)", field_pattern, a,
                   b, "magbake field");
    } else {
      volumes = static_cast<int>(files.size());
      o << "\n    def Volume \"field\"\n    {\n";
      o << "        rel field:B = </" << shot << "/field/B>\n";
      o << "        rel field:density = </" << shot << "/field/density>\n";
      for (const char* grid : {"B", "density"}) {
        o << "\n        def OpenVDBAsset " << quoted(grid) << "\n        {\n";
        o << "            token fieldDataType = " << (grid[0] == 'B' ? "\"float3\"" : "\"float\"") << "\n";
        o << "            token fieldName = " << quoted(grid) << "\n";
        o << "            asset filePath.timeSamples = {\n";
        for (const auto& [frame, path] : files) o << "                " << frame << ": " << path << ",\n";
        o << "            }\n        }\n";
      }
      o << "    }\n";
    }
  }
  // Field lines: the previews' streamlines, one time sample per frame (their number and length
  // change from frame to frame, so the topology is time-sampled too).
  std::size_t line_points = 0;
  if (req.field_lines && magnetic_any) {
    const magnetics::Box3 region = field_line_region(shot_box(geo, frames));
    const std::vector<Vec3> coms = cache->centers_of_mass();
    const std::vector<double> ext = cache->parameter_doubles("external_field");
    const Vec3 applied(ext.at(0), ext.at(1), ext.at(2));
    magnetics::State st;
    st.resize(model);
    std::ostringstream counts, points, colors, extents;
    Progress progress("usd", "field lines", static_cast<int>(frames.size()), g.quiet);
    int done = 0;
    for (const io::CacheFrame& fr : frames) {
      if (interrupt_requested()) {
        progress.finish();
        spdlog::warn("interrupted: {} not written", req.usd);
        return kInterrupted;
      }
      place_frame(model, coms, induced_order, fr, st);
      const std::vector<render::Polyline> lines = trace_field_lines(model, st, applied, region);
      render::Vec3f lo = render::Vec3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
      counts << "                " << fr.frame << ": [";
      points << "                " << fr.frame << ": [";
      colors << "                " << fr.frame << ": [";
      bool first = true;
      for (std::size_t l = 0; l < lines.size(); ++l) {
        counts << (l ? ", " : "") << lines[l].points.size();
        for (std::size_t k = 0; k < lines[l].points.size(); ++k, first = false) {
          const render::Vec3f& p = lines[l].points[k];
          lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
          points << (first ? "" : ", ") << fmt::format("({:.6g}, {:.6g}, {:.6g})", p[0], p[1], p[2]);
          const render::Vec3f& c = lines[l].colors[k];
          colors << (first ? "" : ", ") << fmt::format("({:.3g}, {:.3g}, {:.3g})", c[0], c[1], c[2]);
          ++line_points;
        }
      }
      counts << "],\n";
      points << "],\n";
      colors << "],\n";
      if (lines.empty()) lo = hi = render::Vec3f::Zero();
      extents << "                " << fr.frame << ": [" << vecf(lo) << ", " << vecf(hi) << "],\n";
      progress.update(++done, fr.frame, b);
    }
    progress.finish();
    const double width = 0.002 * region.sizes().maxCoeff();
    o << "\n    def BasisCurves \"field_lines\" (\n        doc = \"streamlines of B as magbake preview draws them, "
         "coloured by log |B| (violet 10 uT, teal 1 mT, yellow 1 T)\"\n    )\n    {\n";
    o << "        uniform token type = \"linear\"\n        uniform token wrap = \"nonperiodic\"\n";
    o << "        int[] curveVertexCounts.timeSamples = {\n" << counts.str() << "        }\n";
    o << "        point3f[] points.timeSamples = {\n" << points.str() << "        }\n";
    o << "        float3[] extent.timeSamples = {\n" << extents.str() << "        }\n";
    o << "        color3f[] primvars:displayColor (\n            interpolation = \"vertex\"\n        )\n";
    o << "        color3f[] primvars:displayColor.timeSamples = {\n" << colors.str() << "        }\n";
    o << "        float[] widths = [" << f(float(width)) << "] (\n            interpolation = \"constant\"\n        )\n";
    o << "    }\n";
  } else if (req.field_lines) {
    spdlog::warn("no magnetic body: no field lines");
  }
  o << "}\n";

  std::error_code ec;
  if (!usd.parent_path().empty()) fs::create_directories(usd.parent_path(), ec);
  const fs::path tmp = fs::path(req.usd + ".partial");
  {
    std::ofstream out(tmp, std::ios::binary);
    out << o.str();
    out.close();
    if (!out) {
      spdlog::error("cannot write {}", tmp.string());
      fs::remove(tmp, ec);
      return kFailure;
    }
  }
  fs::rename(tmp, usd, ec);
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
