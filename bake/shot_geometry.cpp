#include "shot_geometry.h"

namespace magbake::cli {
using magnetics::Vec3;
using render::Vec3f;

// Material colours (linear RGB): permanent magnets red (north half) and blue (south half), as in
// the paper's figures; soft iron grey; other linear materials copper; superconductors pale cyan;
// non-magnetic bodies warm white.
Vec3f material_color(const std::string& kind, bool north) {
  if (kind == "permanent") return north ? Vec3f(0.75f, 0.08f, 0.06f) : Vec3f(0.08f, 0.20f, 0.72f);
  if (kind == "soft") return Vec3f(0.42f, 0.44f, 0.47f);
  if (kind == "linear") return Vec3f(0.72f, 0.38f, 0.16f);
  if (kind == "superconductor") return Vec3f(0.45f, 0.80f, 0.85f);
  return Vec3f(0.78f, 0.74f, 0.64f);
}

ShotGeometry load_geometry(const io::CacheReader& cache) {
  const io::RenderGeometry geo = cache.geometry();
  // A body with inserts is drawn as a translucent casing so its magnets show through.
  std::vector<bool> has_parts(cache.body_names().size(), false);
  for (const auto& s : geo.submeshes) {
    if (s.role == "part") has_parts[s.body] = true;
  }
  ShotGeometry g;
  g.body_points.resize(cache.body_names().size());
  auto vertex = [&](std::int64_t v) { return geo.vertices[v]; };
  for (const io::RenderGeometry::Submesh& sub : geo.submeshes) {
    render::Mesh m;
    m.body = sub.body;
    if (sub.role == "body" && has_parts[m.body] && sub.material_kind == "none") m.alpha = 0.35f;
    Vec3 centre = Vec3::Zero();
    for (std::int64_t v = sub.vertex_begin; v < sub.vertex_begin + sub.vertex_count; ++v) {
      centre += vertex(v);
      g.body_points[m.body].push_back(vertex(v));
    }
    centre /= double(std::max<std::int64_t>(sub.vertex_count, 1));
    const Vec3 dir = sub.magnetization;
    const std::string& kind = sub.material_kind;
    // The scene's colour (sRGB as picked) drawn in the renderer's linear RGB; a magnet with a
    // colour is drawn in it whole.
    std::optional<Vec3f> own;
    if (sub.color) own = sub.color->array().pow(2.2).cast<float>().matrix();
    auto emit = [&](const Vec3& a, const Vec3& b, const Vec3& c, bool north) {
      const Vec3f col = own ? *own : material_color(kind, north);
      for (const Vec3& p : {a, b, c}) m.positions.push_back(p.cast<float>()), m.colors.push_back(col);
    };
    for (std::int64_t t = sub.triangle_begin; t < sub.triangle_begin + sub.triangle_count; ++t) {
      const auto& tri = geo.triangles[t];
      const Vec3 p[3] = {vertex(tri[0]), vertex(tri[1]), vertex(tri[2])};
      if (kind != "permanent" || own) {
        emit(p[0], p[1], p[2], true);
        continue;
      }
      // North half: the side of the magnet the magnetization points to. Triangles crossing the
      // mid-plane are cut along it, so the two halves meet on a straight line.
      double d[3];
      for (int k = 0; k < 3; ++k) d[k] = (p[k] - centre).dot(dir);
      const bool n0 = d[0] >= 0, n1 = d[1] >= 0, n2 = d[2] >= 0;
      if (n0 == n1 && n1 == n2) {
        emit(p[0], p[1], p[2], n0);
        continue;
      }
      // The lone vertex i (on one side) and the other two, in winding order.
      const int i = (n0 != n1 && n0 != n2) ? 0 : (n1 != n0 && n1 != n2) ? 1 : 2;
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      const Vec3 pj = p[i] + (p[j] - p[i]) * (d[i] / (d[i] - d[j]));
      const Vec3 pk = p[i] + (p[k] - p[i]) * (d[i] / (d[i] - d[k]));
      const bool lone_north = d[i] >= 0;
      emit(p[i], pj, pk, lone_north);
      emit(pj, p[j], p[k], !lone_north);
      emit(pj, p[k], pk, !lone_north);
    }
    g.meshes.push_back(std::move(m));
  }
  return g;
}

}  // namespace magbake::cli
