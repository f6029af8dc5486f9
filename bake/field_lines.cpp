#include "field_lines.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

namespace magbake::cli {

using magnetics::Vec3;
using render::Vec3f;

// |B| -> colour for field lines: a log scale from deep violet (10 µT) through teal to yellow (1 T),
// distinct from every material colour.
Vec3f field_line_color(double b) {
  const double t = std::clamp((std::log10(std::max(b, 1e-12)) + 5.0) / 5.0, 0.0, 1.0);
  const Vec3f a(0.35f, 0.05f, 0.55f), m(0.0f, 0.62f, 0.58f), c(1.0f, 0.86f, 0.0f);
  return t < 0.5 ? Vec3f(a + (m - a) * float(2 * t)) : Vec3f(m + (c - m) * float(2 * t - 1));
}

void place_frame(const magnetics::Model& model, const std::vector<Vec3>& coms, const std::vector<int>& induced_order,
                 const io::CacheFrame& fr, magnetics::State& st) {
  for (int b = 0; b < model.body_count; ++b) {
    st.body_pose[b] = magnetics::Pose{fr.orientation[b], fr.position[b] + fr.orientation[b] * coms[b]};
  }
  std::vector<Vec3> induced(model.induced_cells.size());
  for (std::size_t k = 0; k < induced.size(); ++k) induced[k] = fr.induced_moment.at(induced_order[k]);
  magnetics::place(model, st, induced);
}

std::vector<Vec3> body_permanent_moments(const magnetics::Model& model) {
  std::vector<Vec3> out(model.body_count, Vec3::Zero());
  for (int c = 0; c < model.cell_count(); ++c) out[model.cell_body[c]] += model.cell_moment[c];
  return out;
}

std::vector<Vec3> body_moments(const magnetics::Model& model, const std::vector<Vec3>& permanent,
                               const std::vector<int>& induced_order, const io::CacheFrame& fr) {
  std::vector<Vec3> out(model.body_count);
  for (int b = 0; b < model.body_count; ++b) out[b] = fr.orientation[b].normalized() * permanent[b];
  for (std::size_t k = 0; k < model.induced_cells.size(); ++k) {
    out[model.cell_body[model.induced_cells[k]]] += fr.induced_moment.at(induced_order.at(k));
  }
  return out;
}

magnetics::Box3 shot_box(const ShotGeometry& geo, const std::vector<io::CacheFrame>& frames) {
  magnetics::Box3 box;
  for (const io::CacheFrame& fr : frames) {
    for (std::size_t b = 0; b < geo.body_points.size(); ++b) {
      for (const Vec3& p : geo.body_points[b]) box.extend(fr.position[b] + fr.orientation[b] * p);
    }
  }
  return box;
}

magnetics::Box3 field_line_region(const magnetics::Box3& shot) {
  const double half = std::max(shot.sizes().maxCoeff(), 1e-3);
  return magnetics::Box3(shot.center() - Vec3::Constant(half), shot.center() + Vec3::Constant(half));
}

// Streamlines of B (RK4 on the unit direction field) from seeds around each magnet: 20 seeds per
// magnetized body, each traced both ways. A crowded shot (more than kLineSeedBudget / 20 magnetized
// bodies) gets fewer seeds per body (kLineSeedBudget in all, at least 4 each), and its lines end
// where they enter a magnet's bounding sphere instead of running on through chains of magnets:
// the picture stays readable and the tracing cost bounded.
constexpr int kLineSeedBudget = 320;

std::vector<render::Polyline> trace_field_lines(const magnetics::Model& model, const magnetics::State& st,
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
      p.colors.push_back(field_line_color(l.mag[std::min(k, l.mag.size() - 1)]));
    }
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace magbake::cli
