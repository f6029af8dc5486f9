// Magnetic materials and the constitutive laws the dipole method uses for them.
#pragma once

#include "types.h"

namespace magbake::magnetics {

/// How a material becomes magnetized.
enum class MaterialKind : unsigned char {
  kNone,            ///< non-magnetic (plastic, wood, aluminium in statics)
  kPermanent,       ///< hard ferromagnet: fixed magnetization J = remanence * direction
  kLinear,          ///< linear induced: soft ferromagnet, paramagnet or diamagnet (chi > -1)
  kSuperconductor,  ///< ideal type-I superconductor: linear with chi = -1 (perfect diamagnet)
};

/// A magnetic material as the library sees it. Validated by the caller (scene layer).
struct Material {
  MaterialKind kind = MaterialKind::kNone;
  double remanence = 0.0;          ///< |J| = mu0 |M| in tesla (kPermanent only)
  Vec3 direction = Vec3::UnitZ();  ///< unit magnetization direction in the part frame (kPermanent)
  double chi = 0.0;                ///< volume susceptibility, dimensionless (kLinear; -1 for kSuperconductor)
  /// Saturation polarization J_s = mu0 M_s, tesla (kLinear with chi > 0); 0 = linear at any
  /// field. With it, M follows the Fröhlich–Kennelly law M = chi H / (1 + chi |H| / M_s)
  /// (physics.md §13).
  double saturation = 0.0;

  /// True when cells of this material carry an induced moment.
  bool induced() const { return kind == MaterialKind::kLinear || kind == MaterialKind::kSuperconductor; }
  /// Susceptibility actually used: chi for linear materials, -1 for superconductors, 0 otherwise.
  double susceptibility() const {
    if (kind == MaterialKind::kSuperconductor) return -1.0;
    return kind == MaterialKind::kLinear ? chi : 0.0;
  }
  /// Magnetization M = J / mu0 in A/m, part frame (zero unless kPermanent).
  Vec3 magnetization() const {
    return kind == MaterialKind::kPermanent ? Vec3(direction.normalized() * (remanence / kMu0)) : Vec3::Zero();
  }
};

/// Polarizability factor of a small sphere (or cube) of susceptibility chi in its local field:
/// M = 3 chi / (3 + chi) * H_loc (physics-notes §4; the paper's eq. 11 prints chi/(1+chi)).
/// chi = -1 (superconductor) gives -3/2.
inline double effective_susceptibility(double chi) { return 3.0 * chi / (3.0 + chi); }

/// Fröhlich–Kennelly magnetization M(H) = chi H / (1 + chi |H| / ms), A/m, of a material of
/// initial susceptibility chi > 0 and saturation magnetization ms > 0 (A/m); H in A/m, any frame.
inline Vec3 frohlich_kennelly(const Vec3& H, double chi, double ms) { return H * (chi / (1.0 + chi * H.norm() / ms)); }

/// The field H (A/m) at which the Fröhlich–Kennelly law gives magnetization M, |M| < ms:
/// |H| = |M| / (chi (1 - |M| / ms)), along M.
inline Vec3 frohlich_kennelly_inverse(const Vec3& M, double chi, double ms) {
  return M / (chi * (1.0 - M.norm() / ms));
}

}  // namespace magbake::magnetics
