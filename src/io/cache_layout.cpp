#include "cache_layout.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "h5.h"

namespace magbake::io {
namespace {

constexpr hsize_t kAny = std::numeric_limits<hsize_t>::max();  // any extent on this axis

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what); }

std::string shape_text(const std::vector<hsize_t>& s) {
  std::string t = "[";
  for (std::size_t i = 0; i < s.size(); ++i) t += (i ? ", " : "") + (s[i] == kAny ? std::string("*") : std::to_string(s[i]));
  return t + "]";
}

// The shape of dataset `path`; fails when it is missing, not a dataset, or of another rank or
// extent than `want` (kAny matches any extent).
std::vector<hsize_t> expect(hid_t f, const std::string& path, const std::vector<hsize_t>& want) {
  if (!h5::exists(f, path)) fail("missing dataset /" + path);
  {
    h5::Handle o(H5Oopen(f, path.c_str(), H5P_DEFAULT));
    if (!o || H5Iget_type(o.id()) != H5I_DATASET) fail("/" + path + " is not a dataset");
  }
  h5::Handle d(H5Dopen2(f, path.c_str(), H5P_DEFAULT));
  if (!d) fail("cannot open /" + path);
  const std::vector<hsize_t> got = h5::shape(d.id());
  bool ok = got.size() == want.size();
  for (std::size_t i = 0; ok && i < got.size(); ++i) ok = want[i] == kAny || want[i] == got[i];
  if (!ok) fail("/" + path + " has shape " + shape_text(got) + ", expected " + shape_text(want));
  return got;
}

void finite(const std::vector<double>& v, const std::string& path) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) fail("/" + path + " holds a non-finite value at element " + std::to_string(i));
  }
}

void in_range(const std::vector<std::int64_t>& v, std::int64_t lo, std::int64_t hi, const std::string& path) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (v[i] < lo || v[i] >= hi) {
      fail("/" + path + "[" + std::to_string(i) + "] = " + std::to_string(v[i]) + " is outside [" + std::to_string(lo) +
           ", " + std::to_string(hi) + ")");
    }
  }
}

std::vector<double> doubles(hid_t f, const std::string& path, const std::vector<hsize_t>& want) {
  expect(f, path, want);
  std::vector<double> v = h5::read_doubles(f, path);
  finite(v, path);
  return v;
}

std::vector<std::int64_t> ints(hid_t f, const std::string& path, const std::vector<hsize_t>& want) {
  expect(f, path, want);
  return h5::read_ints(f, path);
}

// A /parameters attribute with `count` finite numbers.
void parameter(hid_t params, const std::string& name, std::size_t count) {
  if (H5Aexists(params, name.c_str()) <= 0) fail("missing attribute /parameters@" + name);
  const std::vector<double> v = h5::read_attr_doubles(params, name);
  if (v.size() != count) fail("/parameters@" + name + " holds " + std::to_string(v.size()) + " numbers, expected " + std::to_string(count));
  finite(v, "parameters@" + name);
}

void string_attribute(hid_t obj, const std::string& where, const std::string& name) {
  if (H5Aexists(obj, name.c_str()) <= 0) fail("missing attribute " + where + "@" + name);
  (void)h5::read_attr_string(obj, name);
}

}  // namespace

CacheLayout check_cache_layout(hid_t f, std::int64_t frames_done) {
  CacheLayout L;
  // Scene and parameters.
  {
    if (!h5::exists(f, "parameters")) fail("missing group /parameters");
    h5::Handle p(H5Gopen2(f, "parameters", H5P_DEFAULT));
    if (!p) fail("/parameters is not a group");
    for (const char* n : {"fps", "first_frame", "last_frame", "dt", "near_field"}) parameter(p.id(), n, 1);
    parameter(p.id(), "external_field", 3);
    if (!(h5::read_attr_doubles(p.id(), "fps")[0] > 0)) fail("/parameters@fps must be positive");
    const double first = h5::read_attr_doubles(p.id(), "first_frame")[0];
    if (first != std::floor(first) || std::abs(first) > 1e9) fail("/parameters@first_frame is not a frame number");
    for (const char* n : {"scene_hash", "scene_name"}) string_attribute(p.id(), "/parameters", n);
    expect(f, "parameters/scene_text", {1});
    (void)h5::read_strings(f, "parameters/scene_text");
  }
  // Bodies.
  L.bodies = expect(f, "bodies/name", {kAny})[0];
  (void)h5::read_strings(f, "bodies/name");
  const hsize_t n = L.bodies;
  doubles(f, "bodies/center_of_mass", {n, 3});
  doubles(f, "bodies/mass", {n});
  // Magnetic parts and cells.
  L.parts = expect(f, "magnetics/parts/body", {kAny})[0];
  const hsize_t np = L.parts;
  const std::vector<std::int64_t> part_body = ints(f, "magnetics/parts/body", {np});
  in_range(part_body, 0, std::int64_t(n), "magnetics/parts/body");
  doubles(f, "magnetics/parts/position", {np, 3});
  const std::vector<double> q = doubles(f, "magnetics/parts/orientation", {np, 4});
  for (hsize_t i = 0; i < np; ++i) {
    if (std::hypot(q[4 * i], q[4 * i + 1], q[4 * i + 2]) == 0 && q[4 * i + 3] == 0) {
      fail("/magnetics/parts/orientation[" + std::to_string(i) + "] is a zero quaternion");
    }
  }
  doubles(f, "magnetics/parts/magnetization", {np, 3});
  doubles(f, "magnetics/parts/half", {np, 3});
  doubles(f, "magnetics/parts/chi", {np});
  // Optional (caches before exact surfaces lack them): both or neither, ranges that tile the
  // triangles in order, and triangles with an area (their normals give the charge densities).
  if (h5::exists(f, "magnetics/parts/surface_begin") || h5::exists(f, "magnetics/parts/surface_vertex")) {
    const std::vector<std::int64_t> sb = ints(f, "magnetics/parts/surface_begin", {np + 1});
    const hsize_t nv = expect(f, "magnetics/parts/surface_vertex", {kAny, 3})[0];
    if (nv % 3 != 0) fail("/magnetics/parts/surface_vertex holds " + std::to_string(nv) + " rows, not 3 per triangle");
    if (sb[0] != 0 || sb[np] != std::int64_t(nv / 3)) {
      fail("/magnetics/parts/surface_begin must run from 0 to the " + std::to_string(nv / 3) + " triangles");
    }
    for (hsize_t i = 0; i < np; ++i) {
      if (sb[i + 1] < sb[i]) fail("/magnetics/parts/surface_begin decreases at element " + std::to_string(i + 1));
    }
    const std::vector<double> v = doubles(f, "magnetics/parts/surface_vertex", {nv, 3});
    for (hsize_t t = 0; t < nv / 3; ++t) {
      const double* a = &v[9 * t];
      const double e1[3] = {a[3] - a[0], a[4] - a[1], a[5] - a[2]}, e2[3] = {a[6] - a[0], a[7] - a[1], a[8] - a[2]};
      const double cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2], cz = e1[0] * e2[1] - e1[1] * e2[0];
      if (!(cx * cx + cy * cy + cz * cz > 0)) fail("/magnetics/parts/surface_vertex: triangle " + std::to_string(t) + " has no area");
    }
  }
  L.cells = expect(f, "magnetics/cells/body", {kAny})[0];
  const hsize_t nc = L.cells;
  const std::vector<std::int64_t> cell_body = ints(f, "magnetics/cells/body", {nc});
  in_range(cell_body, 0, std::int64_t(n), "magnetics/cells/body");
  const std::vector<std::int64_t> cell_part = ints(f, "magnetics/cells/part", {nc});
  in_range(cell_part, 0, std::int64_t(np), "magnetics/cells/part");
  for (hsize_t c = 0; c < nc; ++c) {
    if (part_body[cell_part[c]] != cell_body[c]) {
      fail("/magnetics/cells: cell " + std::to_string(c) + " belongs to body " + std::to_string(cell_body[c]) +
           " but its part to body " + std::to_string(part_body[cell_part[c]]));
    }
  }
  ints(f, "magnetics/cells/full", {nc});
  for (const char* name : {"position", "center", "moment"}) doubles(f, std::string("magnetics/cells/") + name, {nc, 3});
  const std::vector<double> half = doubles(f, "magnetics/cells/half", {nc, 3});
  for (hsize_t i = 0; i < 3 * nc; ++i) {
    if (!(half[i] > 0)) fail("/magnetics/cells/half holds a non-positive half edge at cell " + std::to_string(i / 3));
  }
  if (h5::exists(f, "magnetics/cells/ball")) {  // optional: caches before exact balls lack it
    const std::vector<std::int64_t> ball = ints(f, "magnetics/cells/ball", {nc});
    in_range(ball, 0, 2, "magnetics/cells/ball");
    for (hsize_t c = 0; c < nc; ++c) {
      if (ball[c] && !(half[3 * c] == half[3 * c + 1] && half[3 * c] == half[3 * c + 2])) {
        fail("/magnetics/cells/ball: ball cell " + std::to_string(c) + " has unequal radii in /magnetics/cells/half");
      }
    }
  }
  const std::vector<double> volume = doubles(f, "magnetics/cells/volume", {nc});
  for (hsize_t i = 0; i < nc; ++i) {
    if (!(volume[i] > 0)) fail("/magnetics/cells/volume[" + std::to_string(i) + "] is not positive");
  }
  doubles(f, "magnetics/cells/chi", {nc});
  L.induced = expect(f, "magnetics/induced_cells", {kAny})[0];
  const std::vector<std::int64_t> induced = ints(f, "magnetics/induced_cells", {L.induced});
  in_range(induced, 0, std::int64_t(nc), "magnetics/induced_cells");
  {
    std::vector<std::uint8_t> seen(nc, 0);
    for (std::int64_t c : induced) {
      if (seen[c]++) fail("/magnetics/induced_cells lists cell " + std::to_string(c) + " twice");
    }
  }
  // Render geometry.
  const hsize_t nv = expect(f, "geometry/vertices", {kAny, 3})[0];
  doubles(f, "geometry/vertices", {nv, 3});
  const hsize_t nt = expect(f, "geometry/triangles", {kAny, 3})[0];
  in_range(ints(f, "geometry/triangles", {nt, 3}), 0, std::int64_t(nv), "geometry/triangles");
  const hsize_t ns = expect(f, "geometry/submesh_body", {kAny})[0];
  in_range(ints(f, "geometry/submesh_body", {ns}), 0, std::int64_t(n), "geometry/submesh_body");
  auto ranges = [&](const char* begin, const char* count, hsize_t total) {
    const auto b = ints(f, std::string("geometry/") + begin, {ns}), c = ints(f, std::string("geometry/") + count, {ns});
    for (hsize_t s = 0; s < ns; ++s) {
      if (b[s] < 0 || c[s] < 0 || b[s] > std::int64_t(total) || c[s] > std::int64_t(total) - b[s]) {
        fail("/geometry: submesh " + std::to_string(s) + " spans [" + std::to_string(b[s]) + ", +" + std::to_string(c[s]) +
             ") of " + std::to_string(total));
      }
    }
  };
  ranges("submesh_vertex_begin", "submesh_vertex_count", nv);
  ranges("submesh_triangle_begin", "submesh_triangle_count", nt);
  for (const char* name : {"submesh_role", "submesh_material_kind"}) {
    expect(f, std::string("geometry/") + name, {ns});
    (void)h5::read_strings(f, std::string("geometry/") + name);
  }
  doubles(f, "geometry/submesh_magnetization", {ns, 3});
  if (h5::exists(f, "geometry/submesh_color")) {  // optional: caches before scene format 1.1 lack it
    const auto c = doubles(f, "geometry/submesh_color", {ns, 3});
    for (hsize_t s = 0; s < ns; ++s) {
      const bool none = c[3 * s] == -1 && c[3 * s + 1] == -1 && c[3 * s + 2] == -1;
      for (int k = 0; k < 3 && !none; ++k) {
        if (!(c[3 * s + k] >= 0 && c[3 * s + k] <= 1)) {
          fail("/geometry/submesh_color[" + std::to_string(s) + "] is neither an RGB colour in [0, 1] nor -1 -1 -1 (none)");
        }
      }
    }
  }

  // Per-frame series: the readable frames are those every series holds.
  std::int64_t frames = std::max<std::int64_t>(frames_done, 0);
  auto series = [&](const std::string& path, std::vector<hsize_t> tail) {
    tail.insert(tail.begin(), kAny);
    frames = std::min<std::int64_t>(frames, std::int64_t(expect(f, path, tail)[0]));
  };
  series("frames/step", {});
  series("frames/time", {});
  for (const char* s : {"position", "velocity", "angular_velocity", "magnetic_force", "magnetic_torque"}) {
    series(std::string("particles/bodies/") + s + "/value", {n, 3});
  }
  series("particles/bodies/orientation/value", {n, 4});
  if (L.induced > 0) series("magnetics/induced_moment/value", {L.induced, 3});
  // Optional (caches written before sleeping lack them): both or neither.
  const bool has_sleep = h5::exists(f, "particles/bodies/sleep/value");
  if (has_sleep || h5::exists(f, "particles/bodies/sleep_reference/value")) {
    series("particles/bodies/sleep/value", {n, 2});
    series("particles/bodies/sleep_reference/value", {n, 6});
    L.sleep = true;
  }
  // Optional (caches before 2026-12-06 lack them): both or neither.
  const bool has_stuck = h5::exists(f, "contacts/stuck_count");
  if (has_stuck || h5::exists(f, "contacts/stuck")) {
    series("contacts/stuck_count", {});
  }
  frames = std::min<std::int64_t>(frames, std::numeric_limits<int>::max());
  if (has_stuck || h5::exists(f, "contacts/stuck")) {
    const hsize_t rows = expect(f, "contacts/stuck", {kAny, kStuckValues})[0];
    const std::vector<double> count = frames > 0 ? h5::read_rows(f, "contacts/stuck_count", 0, hsize_t(frames))
                                                 : std::vector<double>{};
    L.stuck_begin.assign(1, 0);
    for (std::int64_t k = 0; k < frames; ++k) {
      const double c = count[k];
      if (!(c >= 0 && c <= double(rows) - double(L.stuck_begin.back())) || c != std::floor(c)) {
        fail("/contacts/stuck_count[" + std::to_string(k) + "] does not fit the " + std::to_string(rows) +
             " rows of /contacts/stuck");
      }
      L.stuck_begin.push_back(L.stuck_begin.back() + std::int64_t(c));
    }
  }
  if (frames > 0) {
    const std::vector<double> step = h5::read_rows(f, "frames/step", 0, hsize_t(frames));
    const std::vector<double> time = h5::read_rows(f, "frames/time", 0, hsize_t(frames));
    finite(time, "frames/time");
    for (std::int64_t k = 0; k < frames; ++k) {
      if (!(std::abs(step[k]) <= 2e9) || step[k] != std::floor(step[k])) fail("/frames/step[" + std::to_string(k) + "] is not a frame number");
      if (k > 0 && !(step[k] > step[k - 1])) {
        fail("/frames/step is not increasing at row " + std::to_string(k) + " (" + std::to_string(std::int64_t(step[k - 1])) +
             " then " + std::to_string(std::int64_t(step[k])) + ")");
      }
    }
  }
  L.frames = static_cast<int>(frames);
  return L;
}

}  // namespace magbake::io
