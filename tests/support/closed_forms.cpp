#include "closed_forms.h"

#include <cmath>
#include <numbers>

namespace magbake::testing {
namespace {
constexpr double kMu0 = 4e-7 * std::numbers::pi;

// ln(r - x) with the limit 0 ln 0 = 0 handled by the caller; stable where x ~ r.
double log_r_minus(double r, double x, double q2) {
  const double d = x > 0 ? q2 / (r + x) : r - x;
  return d > 0 ? std::log(d) : 0.0;
}
}  // namespace

Vec3 akoun_yonnet_force(double J1, double J2, const Vec3& h1, const Vec3& h2, const Vec3& d) {
  Vec3 F = Vec3::Zero();
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k)
        for (int l = 0; l < 2; ++l)
          for (int p = 0; p < 2; ++p)
            for (int q = 0; q < 2; ++q) {
              const double sgn = ((i + j + k + l + p + q) % 2) ? -1.0 : 1.0;
              const double u = d[0] + (j ? -1 : 1) * h2[0] - (i ? -1 : 1) * h1[0];
              const double v = d[1] + (l ? -1 : 1) * h2[1] - (k ? -1 : 1) * h1[1];
              const double w = d[2] + (q ? -1 : 1) * h2[2] - (p ? -1 : 1) * h1[2];
              const double r = std::sqrt(u * u + v * v + w * w);
              const double lu = log_r_minus(r, u, v * v + w * w);
              const double lv = log_r_minus(r, v, u * u + w * w);
              // atan(uv / (r w)), with atan(uv/0) = sign(uv) pi/2 at contact.
              const double at = (w == 0.0) ? (u * v == 0.0 ? 0.0 : std::copysign(std::numbers::pi / 2, u * v))
                                           : std::atan(u * v / (r * w));
              // 0 * ln 0 = 0: the products below vanish when the logarithm's argument does.
              const double fx = 0.5 * (v * v - w * w) * lu + u * v * lv + v * w * at + 0.5 * r * u;
              const double fy = 0.5 * (u * u - w * w) * lv + u * v * lu + u * w * at + 0.5 * r * v;
              const double fz = -u * w * lu - v * w * lv + u * v * at - r * w;
              F += sgn * Vec3(fx, fy, fz);
            }
  return J1 * J2 / (4.0 * std::numbers::pi * kMu0) * F;
}

Vec3 furlani_cuboid_field(double J, const Vec3& h, const Vec3& x) {
  // Furlani's form with corners x_m, y_n, z_k (m, n, k in {1, 2}), M_s = J / mu0.
  const double xs[2] = {-h[0], h[0]}, ys[2] = {-h[1], h[1]}, zs[2] = {-h[2], h[2]};
  auto R = [&](double a, double b, double c) { return std::sqrt(a * a + b * b + c * c); };
  double bx = 0, by = 0, bz = 0;
  for (int k = 0; k < 2; ++k) {
    const double dz = x[2] - zs[k];
    for (int m = 0; m < 2; ++m) {
      const double sg = ((k + m) % 2) ? -1.0 : 1.0;
      // Bx: ln[(y - y1) + R1] / [(y - y2) + R2] at x_m.
      {
        const double dx = x[0] - xs[m];
        const double y1 = x[1] - ys[0], y2 = x[1] - ys[1];
        const double r1 = R(dx, y1, dz), r2 = R(dx, y2, dz);
        auto lp = [&](double a, double r) {  // ln(a + r) stable for a < 0
          return a >= 0 ? std::log(a + r) : std::log((dx * dx + dz * dz) / (r - a));
        };
        bx += sg * (lp(y1, r1) - lp(y2, r2));
      }
      // By: the same with x and y exchanged, at y_m.
      {
        const double dy = x[1] - ys[m];
        const double x1 = x[0] - xs[0], x2 = x[0] - xs[1];
        const double r1 = R(x1, dy, dz), r2 = R(x2, dy, dz);
        auto lp = [&](double a, double r) {
          return a >= 0 ? std::log(a + r) : std::log((dy * dy + dz * dz) / (r - a));
        };
        by += sg * (lp(x1, r1) - lp(x2, r2));
      }
      for (int n = 0; n < 2; ++n) {
        const double sg3 = ((k + m + n) % 2) ? -1.0 : 1.0;
        const double dx = x[0] - xs[n], dy = x[1] - ys[m];
        bz += sg3 * (dz == 0.0 ? (dx * dy == 0.0 ? 0.0 : std::copysign(std::numbers::pi / 2, dx * dy))
                                         : std::atan(dx * dy / (dz * R(dx, dy, dz))));
      }
    }
  }
  const double c = J / (4.0 * std::numbers::pi);
  // Furlani's signs: B_x = c * sum (-1)^(k+m) ln(...), B_z = -c * sum (-1)^(k+n+m) atan(...).
  return Vec3(c * bx, c * by, -c * bz);
}

Vec3 point_dipole_field(const Vec3& m, const Vec3& r) {
  const double d = r.norm();
  const Vec3 n = r / d;
  return 1e-7 / (d * d * d) * (3.0 * n * n.dot(m) - m);
}

}  // namespace magbake::testing
