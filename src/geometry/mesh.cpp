// Closed triangle meshes: welding, closedness check, mass properties, fast winding numbers.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>

#include "shapes.h"

#include "magnetics/surface_charge.h"

namespace magbake::geometry {

// Bounding volume hierarchy over triangles with the dipole (first-order) far-field terms of the
// winding number: a cluster seen from afar subtends N . (p - q) / |p - q|³ / (4 pi).
struct MeshShape::Bvh {
  struct Node {
    Vec3 center;        // area-weighted centroid of the cluster
    double radius = 0;  // bounding radius about center
    Vec3 area_normal;   // sum of triangle vector areas (1/2 e1 x e2)
    Mat3 charge_dipole; // column a: sum of A_t n_t[a] (c_t - center), charge dipole for M = e_a
    int begin = 0, end = 0;
    int child = -1;     // first child (second is child + 1), -1 for a leaf
  };
  std::vector<Node> nodes;
  std::vector<int> order;  // triangle indices, cluster-contiguous
};

MeshShape::~MeshShape() = default;
MeshShape::MeshShape(MeshShape&&) noexcept = default;
MeshShape& MeshShape::operator=(MeshShape&&) noexcept = default;

namespace {

constexpr int kLeafTriangles = 8;
constexpr double kBeta = 2.0;  // far-field acceptance: distance > beta * radius

}  // namespace

MeshShape::MeshShape(std::vector<Vec3> vertices, std::vector<Eigen::Vector3i> triangles) {
  if (vertices.empty() || triangles.empty()) throw std::runtime_error("mesh has no triangles");
  // Weld vertices at identical positions (STL and many exporters duplicate them per triangle).
  std::map<std::tuple<double, double, double>, int> index;
  std::vector<int> remap(vertices.size());
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    const auto key = std::make_tuple(vertices[v][0], vertices[v][1], vertices[v][2]);
    auto [it, inserted] = index.emplace(key, static_cast<int>(vertices_.size()));
    if (inserted) vertices_.push_back(vertices[v]);
    remap[v] = it->second;
  }
  for (const auto& t : triangles) {
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= static_cast<int>(vertices.size())) throw std::runtime_error("mesh triangle index out of range");
    }
    Eigen::Vector3i w(remap[t[0]], remap[t[1]], remap[t[2]]);
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2]) continue;  // collapsed by welding
    triangles_.push_back(w);
  }
  // Closed and consistently oriented: every directed edge once, its reverse once.
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : triangles_) {
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  }
  std::size_t boundary = 0, nonmanifold = 0, flipped = 0;
  for (const auto& [e, n] : directed) {
    const auto rev = directed.find({e.second, e.first});
    const int nr = rev == directed.end() ? 0 : rev->second;
    if (n > 1) ++nonmanifold;
    if (nr == 0) ++boundary;
    else if (n != nr) ++flipped;
  }
  if (boundary || nonmanifold || flipped) {
    throw std::runtime_error("mesh is not closed: " + std::to_string(boundary) + " boundary edges, " +
                             std::to_string(nonmanifold) + " non-manifold or inconsistently oriented edges" +
                             (flipped ? ", " + std::to_string(flipped) + " mismatched edge pairs" : "") +
                             " (a magnetized mesh must enclose a volume: repair it, e.g. fill holes)");
  }
  // Mass properties by the divergence theorem over signed tetrahedra (origin, triangle).
  double vol = 0;
  Vec3 first = Vec3::Zero();
  Mat3 second = Mat3::Zero();  // integral of x x^T
  for (const auto& t : triangles_) {
    const Vec3 &a = vertices_[t[0]], &b = vertices_[t[1]], &c = vertices_[t[2]];
    const double v = a.dot(b.cross(c)) / 6.0;
    vol += v;
    first += v * (a + b + c) / 4.0;
    // Covariance of a tetrahedron with one vertex at the origin.
    const Vec3 s = a + b + c;
    second += v / 20.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  if (vol < 0) {  // inside-out: flip every triangle
    for (auto& t : triangles_) std::swap(t[1], t[2]);
    vol = -vol, first = -first, second = -second;
  }
  if (!(vol > 0)) throw std::runtime_error("mesh encloses no volume");
  mass_.volume = vol;
  mass_.centroid = first / vol;
  const Mat3 cov = second - vol * mass_.centroid * mass_.centroid.transpose();
  mass_.inertia = Mat3::Identity() * cov.trace() - cov;
  for (const auto& v : vertices_) bounds_.extend(v);

  // Winding-number hierarchy.
  bvh_ = std::make_unique<Bvh>();
  bvh_->order.resize(triangles_.size());
  std::iota(bvh_->order.begin(), bvh_->order.end(), 0);
  std::vector<Vec3> centroid(triangles_.size()), area(triangles_.size());
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    const auto& t = triangles_[i];
    centroid[i] = (vertices_[t[0]] + vertices_[t[1]] + vertices_[t[2]]) / 3.0;
    area[i] = 0.5 * (vertices_[t[1]] - vertices_[t[0]]).cross(vertices_[t[2]] - vertices_[t[0]]);
  }
  auto& nodes = bvh_->nodes;
  auto& order = bvh_->order;
  auto build = [&](auto&& self, int node, int begin, int end) -> void {
    Box3 bb;
    double wsum = 0;
    Vec3 c = Vec3::Zero(), n = Vec3::Zero();
    for (int q = begin; q < end; ++q) {
      const int i = order[q];
      const double w = area[i].norm();
      wsum += w, c += w * centroid[i], n += area[i];
      bb.extend(centroid[i]);
    }
    c = wsum > 0 ? Vec3(c / wsum) : bb.center();
    double r = 0;
    for (int q = begin; q < end; ++q) {
      const auto& t = triangles_[order[q]];
      for (int k = 0; k < 3; ++k) r = std::max(r, (vertices_[t[k]] - c).norm());
    }
    Mat3 dip = Mat3::Zero();
    for (int q = begin; q < end; ++q) {
      const int i = order[q];
      dip += (centroid[i] - c) * area[i].transpose();
    }
    nodes[node].center = c, nodes[node].radius = r, nodes[node].area_normal = n;
    nodes[node].charge_dipole = dip;
    nodes[node].begin = begin, nodes[node].end = end;
    if (end - begin <= kLeafTriangles) return;
    int axis;
    bb.sizes().maxCoeff(&axis);
    const int mid = begin + (end - begin) / 2;
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end, [&](int a, int b) {
      return centroid[a][axis] < centroid[b][axis] || (centroid[a][axis] == centroid[b][axis] && a < b);
    });
    const int child = static_cast<int>(nodes.size());
    nodes.emplace_back();
    nodes.emplace_back();
    nodes[node].child = child;
    self(self, child, begin, mid);
    self(self, child + 1, mid, end);
  };
  nodes.emplace_back();
  build(build, 0, 0, static_cast<int>(triangles_.size()));
}

bool MeshShape::surface(double, std::vector<Vec3>& vertices, std::vector<Eigen::Vector3i>& triangles) const {
  vertices = vertices_;
  triangles = triangles_;
  return true;
}

bool MeshShape::demag_tensor(const Vec3& p, Mat3& D) const {
  // H(p) = 1/(4 pi) sum_t sigma_t E_t(p) with sigma_t = n_t . M: D = -1/(4 pi) sum_t E_t n_t^T.
  Mat3 S = Mat3::Zero();
  int stack[96];
  int top = 0;
  stack[top++] = 0;
  constexpr double kFar = 8.0;
  while (top > 0) {
    const auto& nd = bvh_->nodes[stack[--top]];
    const Vec3 d = p - nd.center;
    const double dist = d.norm();
    if (dist > kFar * nd.radius) {
      // Charge and charge-dipole terms of the cluster (one column per magnetization axis).
      const double inv3 = 1.0 / (dist * dist * dist);
      const Vec3 u = d / dist;
      S += d * inv3 * nd.area_normal.transpose();
      S += inv3 * (3.0 * u * (u.transpose() * nd.charge_dipole) - nd.charge_dipole);
      continue;
    }
    if (nd.child < 0) {
      for (int q = nd.begin; q < nd.end; ++q) {
        const auto& t = triangles_[bvh_->order[q]];
        const Vec3 &a = vertices_[t[0]], &b = vertices_[t[1]], &c = vertices_[t[2]];
        const Vec3 an = 0.5 * (b - a).cross(c - a);  // area x normal
        S += triangle_field(p, a, b, c) * (an / an.norm()).transpose();
      }
      continue;
    }
    stack[top++] = nd.child;
    stack[top++] = nd.child + 1;
  }
  D = -S / (4.0 * std::numbers::pi);
  return true;
}

double MeshShape::winding_number(const Vec3& p) const {
  double w = 0;
  int stack[96];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const auto& n = bvh_->nodes[stack[--top]];
    const Vec3 d = n.center - p;
    const double dist = d.norm();
    if (dist > kBeta * n.radius) {
      w += n.area_normal.dot(d) / (dist * dist * dist);
      continue;
    }
    if (n.child < 0) {
      for (int q = n.begin; q < n.end; ++q) {
        const auto& t = triangles_[bvh_->order[q]];
        w += magnetics::solid_angle(vertices_[t[0]] - p, vertices_[t[1]] - p, vertices_[t[2]] - p);
      }
      continue;
    }
    stack[top++] = n.child;
    stack[top++] = n.child + 1;
  }
  return w / (4.0 * std::numbers::pi);
}

}  // namespace magbake::geometry
