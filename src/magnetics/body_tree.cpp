#include "body_tree.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "state.h"

namespace magbake::magnetics {
namespace {

struct Builder {
  const std::vector<Vec3>& c;  // root sphere centre per body (world)
  const std::vector<double>& r;
  const std::vector<double>& reach;
  BodyTree& t;
  const std::vector<int>* cluster = nullptr;  // build_over(): items of one cluster stay together
  std::vector<Vec3> cluster_center;           // (ncluster) mean of its items' centres

  // Splits order[b, e) between clusters when it holds more than one: by the clusters' centres
  // along the widest axis of those centres, at the cluster boundary nearest the middle. Returns
  // the split, or -1 when the range is one cluster.
  int split_clusters(int b, int e) {
    const std::vector<int>& k = *cluster;
    bool several = false;
    for (int q = b + 1; q < e && !several; ++q) several = k[t.order[q]] != k[t.order[b]];
    if (!several) return -1;
    Box3 box;
    for (int q = b; q < e; ++q) box.extend(cluster_center[k[t.order[q]]]);
    int axis;
    box.sizes().maxCoeff(&axis);
    std::sort(t.order.begin() + b, t.order.begin() + e, [&](int x, int y) {
      const double cx = cluster_center[k[x]][axis], cy = cluster_center[k[y]][axis];
      return cx < cy || (cx == cy && (k[x] < k[y] || (k[x] == k[y] && x < y)));
    });
    const int mid = b + (e - b) / 2;
    int best = -1;
    for (int q = b + 1; q < e; ++q) {
      if (k[t.order[q]] == k[t.order[q - 1]]) continue;
      if (best < 0 || std::abs(q - mid) < std::abs(best - mid)) best = q;
    }
    return best;
  }

  // Node for order[b, e): returns its index; children are allocated as a pair.
  void fill(int n, int b, int e) {
    Box3 box;
    for (int q = b; q < e; ++q) box.extend(c[t.order[q]]);
    const Vec3 mid = box.center();
    double rad = 0, rch = 0;
    for (int q = b; q < e; ++q) {
      const int body = t.order[q];
      rad = std::max(rad, (c[body] - mid).norm() + r[body]);
      rch = std::max(rch, reach[body]);
    }
    t.center[n] = mid, t.radius[n] = rad, t.reach[n] = rch, t.begin[n] = b, t.end[n] = e;
    if (e - b == 1) {
      t.body[n] = t.order[b];
      t.leaf_of[t.order[b]] = n;
      return;
    }
    int m = cluster ? split_clusters(b, e) : -1;
    if (m < 0) {
      int axis;
      box.sizes().maxCoeff(&axis);
      m = b + (e - b) / 2;
      std::nth_element(t.order.begin() + b, t.order.begin() + m, t.order.begin() + e, [&](int x, int y) {
        return c[x][axis] < c[y][axis] || (c[x][axis] == c[y][axis] && x < y);
      });
    }
    const int k = t.node_count();
    for (int i = 0; i < 2; ++i) {
      t.child.push_back(-1), t.body.push_back(-1), t.begin.push_back(0), t.end.push_back(0);
      t.parent.push_back(n), t.center.emplace_back(Vec3::Zero()), t.radius.push_back(0), t.reach.push_back(0);
    }
    t.child[n] = k;
    fill(k, b, m);
    fill(k + 1, m, e);
  }
};

}  // namespace

void BodyTree::build(const Model& m, const State& s, const std::function<bool(int)>& pick) {
  child.clear(), body.clear(), begin.clear(), end.clear(), parent.clear();
  center.clear(), radius.clear(), reach.clear(), order.clear();
  leaf_of.assign(m.body_count, -1);
  std::vector<Vec3> c(m.body_count, Vec3::Zero());
  std::vector<double> r(m.body_count, 0.0), rch(m.body_count, 0.0);
  for (int b = 0; b < m.body_count; ++b) {
    const int root = m.body_root[b];
    if (root < 0 || (pick && !pick(b))) continue;
    order.push_back(b);
    c[b] = s.body_pose[b].position + s.node_offset[root];
    r[b] = m.node_radius[root];
    rch[b] = m.node_reach[root];
  }
  if (order.empty()) return;
  child.push_back(-1), body.push_back(-1), begin.push_back(0), end.push_back(0);
  parent.push_back(-1), center.emplace_back(Vec3::Zero()), radius.push_back(0), reach.push_back(0);
  Builder{c, r, rch, *this, nullptr, {}}.fill(0, 0, static_cast<int>(order.size()));
}

void BodyTree::build_over(const std::vector<Vec3>& c, const std::vector<double>& r,
                          const std::vector<int>& cluster) {
  assert(c.size() == r.size());
  assert(cluster.empty() || cluster.size() == c.size());
  child.clear(), body.clear(), begin.clear(), end.clear(), parent.clear();
  center.clear(), radius.clear(), reach.clear();
  const int n = static_cast<int>(c.size());
  leaf_of.assign(n, -1);
  order.resize(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  if (n == 0) return;
  const std::vector<double> rch(n, 0.0);
  child.push_back(-1), body.push_back(-1), begin.push_back(0), end.push_back(0);
  parent.push_back(-1), center.emplace_back(Vec3::Zero()), radius.push_back(0), reach.push_back(0);
  Builder builder{c, r, rch, *this, nullptr, {}};
  if (!cluster.empty()) {
    builder.cluster = &cluster;
    const int nk = *std::max_element(cluster.begin(), cluster.end()) + 1;
    builder.cluster_center.assign(nk, Vec3::Zero());
    std::vector<int> count(nk, 0);
    for (int i = 0; i < n; ++i) builder.cluster_center[cluster[i]] += c[i], ++count[cluster[i]];
    for (int k = 0; k < nk; ++k) {
      if (count[k] > 0) builder.cluster_center[k] /= count[k];
    }
  }
  builder.fill(0, 0, n);
}

void BodyTreeSources::aggregate(const BodyTree& t, const Model& m, const Sources& src) {
  const int nn = t.node_count();
  moment.assign(nn, Vec3::Zero());
  active.assign(nn, 0);
  open_radius.assign(nn, 0.0);
  spread.assign(nn, 0.0);
  induced.assign(nn, 0);
  std::vector<double> abs_sum(nn, 0.0), spread_sum(nn, 0.0);  // sum |m_k|, sum q_k |m_k|
  // Children are created after their parents: a reverse sweep sums bottom-up.
  for (int n = nn - 1; n >= 0; --n) {
    if (t.child[n] < 0) {
      const int root = m.body_root[t.body[n]];
      moment[n] = src.node[root];
      active[n] = src.node_active[root];
      abs_sum[n] = moment[n].norm();
      open_radius[n] = t.radius[n];
      induced[n] = m.body_induced.empty() ? 0 : m.body_induced[t.body[n]];
      spread[n] = src.spread.empty() ? 0.0 : src.spread[root];
      // A body whose moments cancel (infinite spread) makes every group holding it open.
      spread_sum[n] = spread[n] == 0.0 ? 0.0
                      : std::isinf(spread[n]) ? std::numeric_limits<double>::infinity()
                                              : spread[n] * abs_sum[n];
    } else {
      const int k = t.child[n];
      moment[n] = moment[k] + moment[k + 1];
      active[n] = active[k] || active[k + 1];
      induced[n] = induced[k] || induced[k + 1];
      abs_sum[n] = abs_sum[k] + abs_sum[k + 1];
      const double net = moment[n].norm();
      open_radius[n] = net > 0.0 ? t.radius[n] * std::max(1.0, abs_sum[n] / net) : std::numeric_limits<double>::infinity();
      spread_sum[n] = spread_sum[k] + spread_sum[k + 1];
      spread[n] = spread_sum[n] == 0.0 ? 0.0 : net > 0.0 ? spread_sum[n] / net : std::numeric_limits<double>::infinity();
    }
  }
}

}  // namespace magbake::magnetics
