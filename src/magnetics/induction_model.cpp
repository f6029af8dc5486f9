#include "induction_model.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <map>
#include <unordered_map>
#include <vector>

#include "cuboid.h"
#include "parallel.h"

namespace magbake::magnetics {

Mat3 dipole_tensor(const Vec3& r) {
  const double d2 = r.squaredNorm();
  const double inv = 1.0 / std::sqrt(d2);
  const double inv5 = inv * inv * inv * inv * inv;
  return kMu0Over4Pi * inv5 * (3.0 * r * r.transpose() - d2 * Mat3::Identity());
}

namespace {

// Mean-field tensors between cells of one part of different sizes (graded cells), part frame,
// by the two half-edges and the offset in units of the smaller half-edge. Not thread-safe.
class GradedTensors {
 public:
  const Mat3& get(const Vec3& ht, const Vec3& hs, const Vec3& offset) {
    const Vec3 unit = ht.cwiseMin(hs);
    std::array<std::int64_t, 9> key;
    for (int a = 0; a < 3; ++a) {
      key[a] = std::bit_cast<std::int64_t>(ht[a]);
      key[3 + a] = std::bit_cast<std::int64_t>(hs[a]);
      key[6 + a] = std::llround(offset[a] / unit[a]);
    }
    auto it = cache_.find(key);
    if (it == cache_.end()) {
      const Vec3 o(key[6] * unit[0], key[7] * unit[1], key[8] * unit[2]);
      it = cache_.emplace(key, cuboid_mean_field_tensor(Cuboid{o, Mat3::Identity(), ht, Vec3::Zero()},
                                                        Cuboid{Vec3::Zero(), Mat3::Identity(), hs, Vec3::Zero()}, 6))
               .first;
    }
    return it->second;
  }

 private:
  std::map<std::array<std::int64_t, 9>, Mat3> cache_;
};

// Mean-field tensor (body frame) of cell j's cuboid over cell i's cuboid, per unit M of j.
// Cells of one part share its lattice axes: tabulated by offset (LatticeTensors for equal
// cells, GradedTensors for cells of different grading levels).
Mat3 mean_tensor(const Model& m, LatticeTensors* lattice, GradedTensors* graded, int i, int j) {
  const int pi = m.cell_part[i], pj = m.cell_part[j];
  if (pi == pj && lattice) {
    const Mat3& R = m.part_rotation[pi];
    const Vec3 d = R.transpose() * (m.cell_center[i] - m.cell_center[j]);
    const Vec3& hi = m.cell_half[i];
    const Vec3& hj = m.cell_half[j];
    if (hi == hj) {
      const Vec3 o = d.cwiseQuotient(2.0 * hi);
      const Eigen::Vector3i off(int(std::lround(o[0])), int(std::lround(o[1])), int(std::lround(o[2])));
      return R * lattice->get(hi, off) * R.transpose();
    }
    return R * graded->get(hi, hj, d) * R.transpose();
  }
  return cuboid_mean_field_tensor(Cuboid{m.cell_center[i], m.part_rotation[pi], m.cell_half[i], Vec3::Zero()},
                                  Cuboid{m.cell_center[j], m.part_rotation[pj], m.cell_half[j], Vec3::Zero()}, 4);
}

bool is_source(const Model& m, int c) { return m.cell_chi[c] != 0.0 || m.cell_moment[c].squaredNorm() > 0.0; }

}  // namespace

void build_induction_model(Model& m, const std::vector<const Solid*>& part_solid, const BuildSettings& settings) {
  const int nind = static_cast<int>(m.induced_cells.size());
  m.induction_near = settings.induction_near;
  m.cell_polarizability.assign(m.cell_count(), Mat3::Zero());
  m.cell_demag.assign(m.cell_count(), Mat3::Zero());
  m.near_begin.assign(nind + 1, 0);
  m.near_cell.clear();
  m.near_tensor.clear();
  if (nind == 0) return;
  LatticeTensors lattice;
  GradedTensors graded;

  // 1. Near rows inside each body: (exact mean field of the source cuboid - point dipole).
  std::vector<std::vector<int>> cand(nind);
  parallel_for_each(nind, 16, [&](int r) {
    const int i = m.induced_cells[r];
    const int b = m.cell_body[i];
    const double hi = m.cell_half[i].maxCoeff();
    for (int j = m.body_cell_begin[b]; j < m.body_cell_begin[b + 1]; ++j) {
      if (j == i || !is_source(m, j)) continue;
      const double lim = settings.induction_near * (hi + m.cell_half[j].maxCoeff());
      if ((m.cell_center[i] - m.cell_center[j]).squaredNorm() < lim * lim) cand[r].push_back(j);
    }
  });
  for (int r = 0; r < nind; ++r) {
    m.near_begin[r + 1] = m.near_begin[r] + static_cast<int>(cand[r].size());
    m.near_cell.insert(m.near_cell.end(), cand[r].begin(), cand[r].end());
  }
  m.near_tensor.resize(m.near_cell.size());
  // Same-lattice entries from the shared table (serial), the others by quadrature (parallel).
  for (int r = 0; r < nind; ++r) {
    const int i = m.induced_cells[r];
    for (int e = m.near_begin[r]; e < m.near_begin[r + 1]; ++e) {
      const int j = m.near_cell[e];
      if (m.cell_part[i] != m.cell_part[j]) continue;
      m.near_tensor[e] = kMu0 * mean_tensor(m, &lattice, &graded, i, j) / (8.0 * m.cell_half[j].prod()) -
                         dipole_tensor(m.cell_position[i] - m.cell_position[j]);
    }
  }
  parallel_for_each(nind, 4, [&](int r) {
    const int i = m.induced_cells[r];
    for (int e = m.near_begin[r]; e < m.near_begin[r + 1]; ++e) {
      const int j = m.near_cell[e];
      if (m.cell_part[i] == m.cell_part[j]) continue;
      m.near_tensor[e] = kMu0 * mean_tensor(m, nullptr, nullptr, i, j) / (8.0 * m.cell_half[j].prod()) -
                         dipole_tensor(m.cell_position[i] - m.cell_position[j]);
    }
  });

  // 2. Self-field and polarizability of every induced cell, part by part.
  for (std::size_t p = 0; p < m.part_body.size(); ++p) {
    if (m.part_chi[p] == 0.0) continue;
    const double chi = m.part_chi[p];
    const Mat3& R = m.part_rotation[p];
    const Pose& pose = m.part_pose[p];
    std::vector<int> rank;  // induced ranks of this part's cells
    for (int r = 0; r < nind; ++r) {
      if (m.cell_part[m.induced_cells[r]] == static_cast<int>(p)) rank.push_back(r);
    }
    Mat3 probe;
    const bool consistent = part_solid[p]->demag_tensor(Vec3::Zero(), probe);
    m.part_consistent[p] = consistent;
    // Own cuboid tensors of the part's cell sizes (one per grading level), looked up serially.
    std::map<std::array<std::int64_t, 3>, Mat3> own_of;
    for (int r : rank) {
      const Vec3& h = m.cell_half[m.induced_cells[r]];
      const std::array<std::int64_t, 3> key{std::bit_cast<std::int64_t>(h[0]), std::bit_cast<std::int64_t>(h[1]),
                                            std::bit_cast<std::int64_t>(h[2])};
      if (!own_of.count(key)) own_of[key] = -R * lattice.get(h, Eigen::Vector3i::Zero()) * R.transpose();
    }
    parallel_for_each(static_cast<int>(rank.size()), 8, [&](int q) {
      const int r = rank[q];
      const int i = m.induced_cells[r];
      const Vec3& h = m.cell_half[i];
      Mat3 N = own_of.at({std::bit_cast<std::int64_t>(h[0]), std::bit_cast<std::int64_t>(h[1]), std::bit_cast<std::int64_t>(h[2])});
      if (consistent) {
        // Exact field of the uniformly magnetized part at the cell ...
        Mat3 D;
        part_solid[p]->demag_tensor(pose.rotation.conjugate() * (m.cell_position[i] - pose.position), D);
        // ... minus what the discrete operator gives there for the same uniform magnetization.
        Mat3 S = Mat3::Zero();
        for (int rj : rank) {
          const int j = m.induced_cells[rj];
          if (j != i) S += m.cell_volume[j] * dipole_tensor(m.cell_position[i] - m.cell_position[j]);
        }
        for (int e = m.near_begin[r]; e < m.near_begin[r + 1]; ++e) {
          const int j = m.near_cell[e];
          if (m.cell_part[j] == static_cast<int>(p)) S += m.cell_volume[j] * m.near_tensor[e];
        }
        N = R * D * R.transpose() + S / kMu0;
      }
      // M = chi (H_loc - N M)  =>  m = v (1 + chi N)^-1 chi H_loc.
      m.cell_demag[i] = N;
      m.cell_polarizability[i] = m.cell_volume[i] * chi * (Mat3::Identity() + chi * N).inverse();
    });
  }

  // 3. Preconditioner: the operator restricted to blocks of consecutive induced cells of one
  // body, factored. The slow modes of the solve live inside high-chi bodies (surface-charge
  // patterns), which these blocks hold exactly; what couples blocks is left to GMRES.
  m.precond_begin.assign(1, 0);
  m.precond_lu.clear();
  m.precond_factor.clear();
  if (settings.induction_block <= 0) return;
  // Bodies that are one block: up to induction_body_block cells, in body order while the
  // distinct ones fit the budget. Bodies of equal layout (cells, their polarizabilities) get
  // equal operators and share a factor below, so they count once here.
  std::unordered_map<std::uint64_t, bool> layout_counted;
  std::int64_t whole_bytes = 0;
  auto layout_hash = [&](int r0, int r1) {
    std::uint64_t h = 1469598103934665603ull ^ static_cast<std::uint64_t>(r1 - r0);
    auto mix = [&](const double* v, int count) {
      for (int k = 0; k < count; ++k) h = (h ^ std::bit_cast<std::uint64_t>(v[k])) * 1099511628211ull;
    };
    for (int r = r0; r < r1; ++r) {
      const int c = m.induced_cells[r];
      mix(m.cell_position[c].data(), 3);
      mix(m.cell_half[c].data(), 3);
      mix(m.cell_polarizability[c].data(), 9);
    }
    return h;
  };
  for (int r = 0; r < nind;) {
    const int b = m.cell_body[m.induced_cells[r]];
    int end = r;
    while (end < nind && m.cell_body[m.induced_cells[end]] == b) ++end;
    int nb = (end - r + settings.induction_block - 1) / settings.induction_block;
    if (nb > 1 && end - r <= settings.induction_body_block) {
      const std::uint64_t key = layout_hash(r, end);
      const std::int64_t bytes = layout_counted.count(key) ? 0 : 72 * std::int64_t(end - r) * (end - r);
      if (whole_bytes + bytes <= settings.induction_block_bytes) {
        whole_bytes += bytes;
        layout_counted[key] = true;
        nb = 1;
      }
    }
    for (int k = 0; k < nb; ++k) m.precond_begin.push_back(r + static_cast<int>((std::int64_t(end - r) * (k + 1)) / nb));
    r = end;
  }
  const int nblock = static_cast<int>(m.precond_begin.size()) - 1;
  // Eigen blocks its dense products (inside the LU) by the CPU's cache sizes, read with cpuid:
  // the summation order, and so the rounding of every induced moment, would depend on the
  // machine (the same binary baked different caches on an Intel and an AMD VM). Fixed sizes
  // make the factors a function of the model alone (Determinism.ResultsDoNotDependOnTheMachines
  // CacheSizes). The values are typical of current x86 cores; speed hardly depends on them.
  Eigen::setCpuCacheSizes(32 * 1024, 512 * 1024, 8 * 1024 * 1024);
  // The operator of block k, body frame: a pure function of the model.
  auto block_matrix = [&](int k) {
    const int r0 = m.precond_begin[k], n = m.precond_begin[k + 1] - r0;
    Eigen::MatrixXd A = Eigen::MatrixXd::Identity(3 * n, 3 * n);
    for (int a = 0; a < n; ++a) {
      const int i = m.induced_cells[r0 + a];
      const Mat3 P = m.cell_polarizability[i] / kMu0;
      for (int c = 0; c < n; ++c) {
        if (c == a) continue;
        const int j = m.induced_cells[r0 + c];
        A.block<3, 3>(3 * a, 3 * c) = -P * dipole_tensor(m.cell_position[i] - m.cell_position[j]);
      }
      for (int e = m.near_begin[r0 + a]; e < m.near_begin[r0 + a + 1]; ++e) {
        const int j = m.near_cell[e];
        // Near sources inside the block: induced cells of this body, found by rank.
        const auto it = std::lower_bound(m.induced_cells.begin() + r0, m.induced_cells.begin() + r0 + n, j);
        if (it == m.induced_cells.begin() + r0 + n || *it != j) continue;
        const int c = static_cast<int>(it - (m.induced_cells.begin() + r0));
        A.block<3, 3>(3 * a, 3 * c) -= P * m.near_tensor[e];
      }
    }
    return A;
  };
  // Blocks with equal operators (bodies of one shape, material and cell layout) share one
  // factorization: at 3000 bodies, half of them steel balls, the per-block matrices and factors
  // took 445 MB. Found by a hash of the matrix and confirmed by comparing the matrices, so
  // sharing never changes a result; the first block of each distinct operator is factored
  // (deterministic for any thread count).
  std::vector<std::uint64_t> hash(nblock);
  parallel_for_each(nblock, 1, [&](int k) {
    const Eigen::MatrixXd A = block_matrix(k);
    std::uint64_t h = 1469598103934665603ull ^ static_cast<std::uint64_t>(A.rows());
    const auto* bytes = reinterpret_cast<const unsigned char*>(A.data());
    const std::size_t nbytes = sizeof(double) * static_cast<std::size_t>(A.size());
    for (std::size_t i = 0; i < nbytes; ++i) h = (h ^ bytes[i]) * 1099511628211ull;  // FNV-1a
    hash[k] = h;
  });
  std::vector<int> candidate(nblock, -1);  // the first earlier block with the same hash
  {
    std::unordered_map<std::uint64_t, int> first;
    for (int k = 0; k < nblock; ++k) {
      const auto [it, fresh] = first.emplace(hash[k], k);
      if (!fresh) candidate[k] = it->second;
    }
  }
  std::vector<std::uint8_t> same(nblock, 0);
  parallel_for_each(nblock, 1, [&](int k) {
    if (candidate[k] >= 0) same[k] = block_matrix(k) == block_matrix(candidate[k]);
  });
  m.precond_factor.assign(nblock, -1);
  std::vector<int> factored;  // the block of each factorization
  for (int k = 0; k < nblock; ++k) {
    if (same[k]) {
      m.precond_factor[k] = m.precond_factor[candidate[k]];
    } else {
      m.precond_factor[k] = static_cast<int>(factored.size());
      factored.push_back(k);
    }
  }
  m.precond_lu.resize(factored.size());
  parallel_for_each(static_cast<int>(factored.size()), 1,
                    [&](int f) { m.precond_lu[f].compute(block_matrix(factored[f])); });
}

}  // namespace magbake::magnetics
