#include "surface_charge.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

namespace magbake::magnetics {

double solid_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double num = a.dot(b.cross(c));
  const double den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
  return 2.0 * std::atan2(num, den);
}

namespace {

// E of one triangle, with its unit normal n given; also returns the solid-angle term n . E.
inline Vec3 triangle_field_n(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& n, double& nE) {
  // Normal part: minus the signed solid angle (positive on the side n points to).
  nE = -solid_angle(a - x, b - x, c - x);
  Vec3 E = nE * n;
  // In-plane part: outward edge normals times the line integral of 1/R along each edge, in the
  // form without cancellation on either side of the edge's foot point.
  const Vec3* v[3] = {&a, &b, &c};
  for (int e = 0; e < 3; ++e) {
    const Vec3& p = *v[e];
    const Vec3& q = *v[(e + 1) % 3];
    const Vec3 t = (q - p).normalized();
    const double s1 = (p - x).dot(t), s2 = (q - x).dot(t);
    const double r1 = (p - x).norm(), r2 = (q - x).norm();
    const double L = s1 > 0 ? std::log((r2 + s2) / (r1 + s1)) : std::log((r1 - s1) / (r2 - s2));
    E += L * t.cross(n);
  }
  return E;
}

}  // namespace

Vec3 triangle_field(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).normalized();
  double nE;
  return triangle_field_n(x, a, b, c, n, nE);
}

Vec3 surface_b_field(const Vec3* vertex, const double* sigma, int ntri, const Vec3& M, const Vec3& x) {
  Vec3 H = Vec3::Zero();
  double angle = 0;  // sum of n . E: -4pi inside (x - y points against the outward n), 0 outside
  for (int t = 0; t < ntri; ++t) {
    const Vec3 &a = vertex[3 * t], &b = vertex[3 * t + 1], &c = vertex[3 * t + 2];
    const Vec3 n = (b - a).cross(c - a).normalized();
    double nE;
    const Vec3 E = triangle_field_n(x, a, b, c, n, nE);
    H += sigma[t] * E;
    angle += nE;
  }
  H /= 4.0 * std::numbers::pi;
  // Inside when the faces' solid angles sum to 4pi (2pi exactly on the surface: outside wins).
  if (angle < -2.0 * std::numbers::pi - 1e-9) H += M;
  return kMu0 * H;
}

bool SurfaceMesh::build(const Vec3* vertex, const double* sigma, int ntri, const Vec3& M) {
  *this = SurfaceMesh{};
  magnetization = M;
  std::map<std::tuple<double, double, double>, int> index;
  auto corner = [&](const Vec3& v) {
    auto [it, inserted] = index.emplace(std::make_tuple(v[0], v[1], v[2]), static_cast<int>(point.size()));
    if (inserted) point.push_back(v);
    return it->second;
  };
  std::vector<Eigen::Vector3i> faces(ntri);
  std::vector<Vec3> normal(ntri);
  for (int t = 0; t < ntri; ++t) {
    faces[t] = Eigen::Vector3i(corner(vertex[3 * t]), corner(vertex[3 * t + 1]), corner(vertex[3 * t + 2]));
    normal[t] = (point[faces[t][1]] - point[faces[t][0]]).cross(point[faces[t][2]] - point[faces[t][0]]).normalized();
  }
  // Edges and their weights.
  std::map<std::pair<int, int>, int> edge_of;  // (low, high) corner -> edge
  std::vector<Eigen::Vector2i> all_edges;
  std::vector<Vec3> weight;
  std::vector<int> uses;
  for (int t = 0; t < ntri; ++t) {
    for (int e = 0; e < 3; ++e) {
      const int p = faces[t][e], q = faces[t][(e + 1) % 3];
      auto [it, inserted] = edge_of.emplace(std::minmax(p, q), static_cast<int>(all_edges.size()));
      if (inserted) {
        all_edges.emplace_back(p, q);
        weight.push_back(Vec3::Zero());
        uses.push_back(0);
      }
      // This triangle's outward in-plane normal of the edge, traversed p -> q.
      weight[it->second] += sigma[t] * (point[q] - point[p]).normalized().cross(normal[t]);
      ++uses[it->second];
    }
  }
  for (int u : uses) {
    if (u != 2) return false;
  }
  const double scale = M.norm();
  for (std::size_t e = 0; e < all_edges.size(); ++e) {
    if (weight[e].norm() <= 1e-12 * scale) continue;  // inside a flat patch of equal charge
    edge.push_back(all_edges[e]);
    edge_tangent.push_back((point[all_edges[e][1]] - point[all_edges[e][0]]).normalized());
    edge_weight.push_back(weight[e]);
  }
  // Groups: one plane (normal and offset) and one charge density, to 1e-9 (rounded keys; a
  // group split by rounding is only slower).
  double size = 0;
  for (const Vec3& p : point) size = std::max(size, p.cwiseAbs().maxCoeff());
  auto key = [&](int t) {
    auto r = [](double v) { return static_cast<long long>(std::llround(v * 1e9)); };
    const Vec3& n = normal[t];
    return std::make_tuple(r(n[0]), r(n[1]), r(n[2]), r(n.dot(point[faces[t][0]]) / size), r(sigma[t] / scale));
  };
  std::map<std::tuple<long long, long long, long long, long long, long long>, int> group_of;
  std::vector<int> group(ntri);
  for (int t = 0; t < ntri; ++t) {
    auto [it, inserted] = group_of.emplace(key(t), static_cast<int>(group_weight.size()));
    if (inserted) group_weight.push_back(sigma[t] * normal[t]);
    group[t] = it->second;
  }
  group_charged.assign(group_weight.size(), 1);
  for (std::size_t g = 0; g < group_weight.size(); ++g) {
    // Exactly zero only: a group whose charge is zero up to rounding keeps its share.
    if (group_weight[g] != Vec3::Zero()) continue;
    group_charged[g] = 0;
  }
  bounds = Box3();
  for (const Vec3& p : point) bounds.extend(p);
  group_begin.assign(group_weight.size() + 1, 0);
  for (int t = 0; t < ntri; ++t) ++group_begin[group[t] + 1];
  for (std::size_t g = 0; g < group_weight.size(); ++g) group_begin[g + 1] += group_begin[g];
  face.resize(ntri);
  std::vector<int> fill(group_begin.begin(), group_begin.end() - 1);
  for (int t = 0; t < ntri; ++t) face[fill[group[t]]++] = faces[t];
  // Group boundaries: a group's inner edges are run both ways by its faces and cancel.
  loop_begin.assign(group_weight.size() + 1, 0);
  for (std::size_t g = 0; g < group_weight.size(); ++g) {
    std::map<std::pair<int, int>, int> run;  // directed edge -> count
    for (int f = group_begin[g]; f < group_begin[g + 1]; ++f) {
      for (int e = 0; e < 3; ++e) ++run[{face[f][e], face[f][(e + 1) % 3]}];
    }
    for (int f = group_begin[g]; f < group_begin[g + 1]; ++f) {
      for (int e = 0; e < 3; ++e) {
        const int p = face[f][e], q = face[f][(e + 1) % 3];
        if (run.count({q, p}) != 0) continue;
        loop_edge.emplace_back(p, q);
        loop_length.push_back((point[q] - point[p]).norm());
        loop_tangent.push_back((point[q] - point[p]) / loop_length.back());
      }
    }
    loop_begin[g + 1] = static_cast<int>(loop_edge.size());
  }
  return true;
}

namespace {

// B (tesla) of the surface at x and, with kGradient, its gradient G_ij = dB_i/dx_j (T/m): one
// pass over the shared corners, the weighted edges and the flat groups, so the field and its
// gradient come from the same terms in the same order.
template <bool kGradient>
Vec3 surface_field(const SurfaceMesh& sm, const Vec3& x, std::vector<double>& d, Mat3* G) {
  const int np = static_cast<int>(sm.point.size());
  d.resize(np);
  for (int v = 0; v < np; ++v) d[v] = (sm.point[v] - x).norm();
  Vec3 H = Vec3::Zero();
  Mat3 J = Mat3::Zero();  // dH_i/dx_j times 4pi
  for (std::size_t e = 0; e < sm.edge.size(); ++e) {
    const int a = sm.edge[e][0], b = sm.edge[e][1];
    const Vec3& t = sm.edge_tangent[e];
    const Vec3 pa = sm.point[a] - x, pb = sm.point[b] - x;
    const double s1 = pa.dot(t), s2 = pb.dot(t);
    const double num = s1 > 0 ? d[b] + s2 : d[a] - s1, den = s1 > 0 ? d[a] + s1 : d[b] - s2;
    // On the edge itself the field is logarithmically infinite: that edge is left out there
    // (a voxel or probe exactly on a facet edge gets a finite value, not NaN).
    if (!(num > 0 && den > 0)) continue;
    H += std::log(num / den) * sm.edge_weight[e];
    if constexpr (kGradient) {
      // d r_k/dx = -u_k (u_k = unit vector from x to corner k), d s_k/dx = -t.
      const Vec3 ua = pa / d[a], ub = pb / d[b];
      const Vec3 grad = s1 > 0 ? Vec3((ua + t) / den - (ub + t) / num) : Vec3((t - ua) / num - (t - ub) / den);
      J += sm.edge_weight[e] * grad.transpose();
    }
  }
  double angle = 0;
  // Outside the corners' box x cannot be inside: uncharged groups are then skipped.
  const bool maybe_inside = sm.bounds.contains(x);
  for (std::size_t g = 0; g + 1 < sm.group_begin.size(); ++g) {
    if (!maybe_inside && !sm.group_charged[g]) continue;
    // Half solid angles add: multiply (den + i num) of the group's triangles, kept at unit scale.
    double X = 1, Y = 0;
    for (int f = sm.group_begin[g]; f < sm.group_begin[g + 1]; ++f) {
      const int i = sm.face[f][0], j = sm.face[f][1], k = sm.face[f][2];
      const Vec3 a = sm.point[i] - x, b = sm.point[j] - x, c = sm.point[k] - x;
      const double num = a.dot(b.cross(c));
      const double den = d[i] * d[j] * d[k] + a.dot(b) * d[k] + a.dot(c) * d[j] + b.dot(c) * d[i];
      const double nx = X * den - Y * num, ny = X * num + Y * den;
      const double s = std::max(std::abs(nx), std::abs(ny));
      if (!(s > 0)) continue;  // the target on a corner: this triangle subtends nothing
      X = nx / s, Y = ny / s;
    }
    const double nE = -2.0 * std::atan2(Y, X);
    H += nE * sm.group_weight[g];
    angle += nE;
    if (kGradient && sm.group_charged[g]) {
      // grad of the solid angle = sum over the boundary of the line integral of
      // dl x (x - y)/|x - y|^3 (the field of a unit current loop); n . E is minus the solid angle.
      Vec3 grad = Vec3::Zero();
      for (int e = sm.loop_begin[g]; e < sm.loop_begin[g + 1]; ++e) {
        const int a = sm.loop_edge[e][0], b = sm.loop_edge[e][1];
        const Vec3 pa = sm.point[a] - x;
        const Vec3& t = sm.loop_tangent[e];
        const double len = sm.loop_length[e];
        const double s1 = pa.dot(t), s2 = s1 + len;
        const Vec3 txp = pa.cross(t);  // t x (x - a)
        double f;
        if (s1 * s2 > 0) {
          // (s2/r2 - s1/r1)/rho^2 without cancellation when x is beyond either end.
          const double den = d[a] * d[b] * (s2 * d[a] + s1 * d[b]);
          if (!(den != 0)) continue;  // on a corner
          f = len * (s1 + s2) / den;
        } else {
          const double rho2 = txp.squaredNorm();
          if (!(rho2 > 0)) continue;  // on the edge: infinite, left out
          f = (s2 / d[b] - s1 / d[a]) / rho2;
        }
        grad += f * txp;
      }
      J -= sm.group_weight[g] * grad.transpose();
    }
  }
  H /= 4.0 * std::numbers::pi;
  if (maybe_inside && angle < -2.0 * std::numbers::pi - 1e-9) H += sm.magnetization;
  if constexpr (kGradient) *G = (kMu0 / (4.0 * std::numbers::pi)) * J;
  return kMu0 * H;
}

}  // namespace

Vec3 SurfaceMesh::b_field(const Vec3& x, std::vector<double>& d) const { return surface_field<false>(*this, x, d, nullptr); }

void SurfaceMesh::b_field_gradient(const Vec3& x, std::vector<double>& d, Vec3& B, Mat3& G) const {
  B = surface_field<true>(*this, x, d, &G);
}

}  // namespace magbake::magnetics
