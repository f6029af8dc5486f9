#include "cache.h"

#include <cmath>
#include <filesystem>
#include <map>

#include "cache_layout.h"
#include "geometry/shapes.h"

namespace magbake::io {
namespace {

using h5::Handle;

constexpr const char* kFormat = "magbake-cache";
constexpr int kFormatVersion = 1;

// Per-body frame series: name, components, unit (H5MD unit grammar; T is tera there, so tesla
// never appears; N = kg m s-2).
struct Series {
  const char* name;
  int components;
  const char* unit;
};
constexpr Series kBodySeries[] = {
    {"position", 3, "m"},        {"orientation", 4, ""},          {"velocity", 3, "m s-1"},
    {"angular_velocity", 3, "s-1"}, {"magnetic_force", 3, "kg m s-2"}, {"magnetic_torque", 3, "kg m2 s-2"},
    // Sleeping: state (0 awake, 1 resting, 2 asleep) and seconds at rest; the
    // magnetic force and torque a sleeping body fell asleep with. Optional for readers (caches
    // before them have neither: every body awake).
    {"sleep", 2, ""}, {"sleep_reference", 6, ""}};
constexpr std::size_t kRequiredBodySeries = 6;  // the rest are optional when read
constexpr Series kObservables[] = {{"kinetic_energy", 1, "kg m2 s-2"},      {"gravity_energy", 1, "kg m2 s-2"},
                                   {"magnetic_energy", 1, "kg m2 s-2"},     {"momentum", 3, "kg m s-1"},
                                   {"angular_momentum", 3, "kg m2 s-1"},    {"magnetics_seconds", 1, "s"},
                                   {"rigid_seconds", 1, "s"},               {"cells_visited", 1, ""},
                                   {"induction_iterations", 1, ""},         {"induction_residual", 1, ""},
                                   {"substeps", 1, ""},                     {"energy_drift", 1, "kg m2 s-2"},
                                   {"max_speed", 1, "m s-1"},               {"max_penetration", 1, "m"},
                                   {"sleeping", 1, ""},                     {"body_steps", 1, ""},
                                   {"applied_field", 3, "T"}};
// "sleeping", "body_steps" and "applied_field" are optional when read (older caches lack them;
// CacheReader::applied_field falls back to /parameters@external_field).
constexpr std::size_t kRequiredObservables = 14;

std::vector<double> flat(const std::vector<Vec3>& v) {
  std::vector<double> out;
  out.reserve(3 * v.size());
  for (const Vec3& x : v) out.insert(out.end(), {x[0], x[1], x[2]});
  return out;
}

}  // namespace

bool is_hdf5_file(const std::string& path) { return H5Fis_hdf5(path.c_str()) > 0; }

const char* status_name(BakeStatus s) {
  switch (s) {
    case BakeStatus::kRunning: return "running (or killed)";
    case BakeStatus::kComplete: return "complete";
    case BakeStatus::kInterrupted: return "interrupted (resumable)";
    case BakeStatus::kFailed: return "failed";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------
struct CacheWriter::Impl {
  Handle file;
  std::vector<Handle> body_series;   // kBodySeries order
  std::vector<Handle> observables;   // kObservables order
  Handle step, time, induced, frames_done, status;
  Handle stuck_count, stuck;         // /contacts
  hsize_t stuck_rows = 0;            // rows of /contacts/stuck written
  const scene::Scene* scene = nullptr;
  std::size_t ninduced = 0;
};

CacheWriter::CacheWriter(const std::string& path, const scene::Scene& sc, const magnetics::Model& model,
                         const std::string& version)
    : impl_(std::make_unique<Impl>()) {
  h5::quiet();
  Impl& m = *impl_;
  m.scene = &sc;
  const std::size_t n = sc.bodies.size();
  Handle fapl(H5Pcreate(H5P_FILE_ACCESS));
  h5::check(H5Pset_libver_bounds(fapl.id(), H5F_LIBVER_LATEST, H5F_LIBVER_LATEST), "libver bounds");
  m.file = Handle(h5::check_id(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.id()), "create " + path));
  const hid_t f = m.file.id();

  // Identification (H5MD 1.1 header) and the scene as it was baked.
  h5::attr_string(f, "format", kFormat);
  h5::attr_int(f, "format_version", {kFormatVersion});
  {
    Handle h5md = h5::create_group(f, "h5md");
    h5::attr_int(h5md.id(), "version", {1, 1});
    Handle author = h5::create_group(h5md.id(), "author");
    h5::attr_string(author.id(), "name", "magbake");
    Handle creator = h5::create_group(h5md.id(), "creator");
    h5::attr_string(creator.id(), "name", "magbake");
    h5::attr_string(creator.id(), "version", version);
  }
  {
    Handle p = h5::create_group(f, "parameters");
    h5::write_strings(p.id(), "scene_text", {sc.text});
    h5::attr_string(p.id(), "scene_name", sc.name);
    h5::attr_string(p.id(), "scene_file", sc.file);
    h5::attr_string(p.id(), "scene_hash", sc.hash);
    h5::attr_string(p.id(), "magbake_version", version);
    h5::attr_string(p.id(), "hdf5_version", h5::library_version());
    h5::attr_string(p.id(), "scene_length_unit", sc.length_unit);
    h5::attr_string(p.id(), "scene_angle_unit", sc.angle_unit);
    h5::attr_double(p.id(), "fps", {sc.fps});
    h5::attr_int(p.id(), "first_frame", {sc.first_frame});
    h5::attr_int(p.id(), "last_frame", {sc.last_frame});
    h5::attr_double(p.id(), "dt", {sc.dt});
    h5::attr_double(p.id(), "sleep_time", {sc.sleep_time});  // s, 0 = no body sleeps
    h5::attr_double(p.id(), "gravity", {sc.gravity[0], sc.gravity[1], sc.gravity[2]});
    const auto& mg = sc.magnetics;
    h5::attr_string(p.id(), "quality", mg.quality);
    h5::attr_double(p.id(), "cell_size", {mg.cell_size.value_or(0.0)});
    h5::attr_int(p.id(), "cells_per_extent", {mg.cells_per_extent});
    h5::attr_double(p.id(), "theta", {mg.theta});
    h5::attr_double(p.id(), "near_field", {mg.near_field});
    h5::attr_int(p.id(), "near_field_order", {mg.near_field_order});
    h5::attr_double(p.id(), "induction_near", {model.induction_near});
    h5::attr_string(p.id(), "induction", mg.induction);
    h5::attr_double(p.id(), "induction_tolerance", {mg.induction_tolerance});
    h5::attr_double(p.id(), "external_field", {mg.external_field[0], mg.external_field[1], mg.external_field[2]});
  }

  // Body constants.
  {
    Handle b = h5::create_group(f, "bodies");
    std::vector<std::string> names, motions, shapes, materials;
    std::vector<double> mass, com, inertia, friction, restitution;
    for (const auto& body : sc.bodies) {
      names.push_back(body.name);
      motions.push_back(body.motion == scene::Motion::kDynamic   ? "dynamic"
                        : body.motion == scene::Motion::kStatic ? "static"
                                                                : "kinematic");
      shapes.push_back(body.shape.describe());
      materials.push_back(body.material >= 0 ? sc.materials[body.material].name : "");
      mass.push_back(body.mass);
      com.insert(com.end(), {body.com[0], body.com[1], body.com[2]});
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) inertia.push_back(body.inertia(r, c));
      friction.push_back(body.friction);
      restitution.push_back(body.restitution);
    }
    h5::write_strings(b.id(), "name", names);
    h5::write_strings(b.id(), "motion", motions);
    h5::write_strings(b.id(), "shape", shapes);
    h5::write_strings(b.id(), "material", materials);
    h5::write_doubles(b.id(), "mass", {n}, mass.data(), "kg");
    h5::write_doubles(b.id(), "center_of_mass", {n, 3}, com.data(), "m");
    h5::write_doubles(b.id(), "inertia", {n, 3, 3}, inertia.data(), "kg m2");
    h5::write_doubles(b.id(), "friction", {n}, friction.data());
    h5::write_doubles(b.id(), "restitution", {n}, restitution.data());
  }

  // Render geometry: every body's shape and parts as triangle meshes in the body frame.
  {
    Handle g = h5::create_group(f, "geometry");
    std::vector<double> verts, magnetization;
    std::vector<std::int64_t> tris, body, vbegin, vcount, tbegin, tcount;
    std::vector<std::string> role, kind;
    // One tessellation per distinct shape (bodies of one scene shape share it), and the arrays
    // sized before they are filled: 3000 spheres took 300 MB here while vectors doubled.
    std::map<const geometry::Shape*, geometry::Tessellation> tess;
    auto tessellation = [&](const scene::ShapeDesc& shape) -> const geometry::Tessellation& {
      auto it = tess.find(shape.shape.get());
      if (it == tess.end()) it = tess.emplace(shape.shape.get(), geometry::tessellate(*shape.shape, 48)).first;
      return it->second;
    };
    {
      std::size_t nv = 0, nt = 0, nsub = 0;
      auto count = [&](const scene::ShapeDesc& shape) {
        const geometry::Tessellation& t = tessellation(shape);
        nv += t.vertices.size(), nt += t.triangles.size(), ++nsub;
      };
      for (const auto& b : sc.bodies) {
        count(b.shape);
        for (const auto& p : b.parts) count(p.shape);
      }
      verts.reserve(3 * nv), tris.reserve(3 * nt), magnetization.reserve(3 * nsub);
      for (auto* v : {&body, &vbegin, &vcount, &tbegin, &tcount}) v->reserve(nsub);
    }
    std::vector<double> color;  // -1 -1 -1: none given
    color.reserve(3 * body.capacity());
    auto add = [&](int bi, const scene::ShapeDesc& shape, const magnetics::Pose& pose, int mat, const Vec3& mag,
                   const char* r, const std::optional<Vec3>& col) {
      const geometry::Tessellation& t = tessellation(shape);
      const std::int64_t v0 = static_cast<std::int64_t>(verts.size() / 3);
      body.push_back(bi);
      vbegin.push_back(v0);
      vcount.push_back(static_cast<std::int64_t>(t.vertices.size()));
      tbegin.push_back(static_cast<std::int64_t>(tris.size() / 3));
      tcount.push_back(static_cast<std::int64_t>(t.triangles.size()));
      for (const Vec3& v : t.vertices) {
        const Vec3 p = pose.apply(v);
        verts.insert(verts.end(), {p[0], p[1], p[2]});
      }
      for (const auto& tr : t.triangles) tris.insert(tris.end(), {v0 + tr[0], v0 + tr[1], v0 + tr[2]});
      role.push_back(r);
      kind.push_back(mat >= 0 ? sc.materials[mat].kind_name : "none");
      magnetization.insert(magnetization.end(), {mag[0], mag[1], mag[2]});
      const Vec3 c = col.value_or(Vec3::Constant(-1));
      color.insert(color.end(), {c[0], c[1], c[2]});
    };
    for (std::size_t i = 0; i < n; ++i) {
      const auto& b = sc.bodies[i];
      add(int(i), b.shape, magnetics::Pose{}, b.material, b.magnetization, "body", b.color);
      for (const auto& p : b.parts) {
        add(int(i), p.shape, p.pose, p.material, p.magnetization, "part",
            p.material >= 0 ? sc.materials[p.material].color : std::nullopt);
      }
    }
    const hsize_t ns = body.size();
    h5::write_doubles(g.id(), "vertices", {verts.size() / 3, 3}, verts.data(), "m");
    h5::write_ints(g.id(), "triangles", {tris.size() / 3, 3}, tris.data());
    h5::write_ints(g.id(), "submesh_body", {ns}, body.data());
    h5::write_ints(g.id(), "submesh_vertex_begin", {ns}, vbegin.data());
    h5::write_ints(g.id(), "submesh_vertex_count", {ns}, vcount.data());
    h5::write_ints(g.id(), "submesh_triangle_begin", {ns}, tbegin.data());
    h5::write_ints(g.id(), "submesh_triangle_count", {ns}, tcount.data());
    h5::write_strings(g.id(), "submesh_role", role);
    h5::write_strings(g.id(), "submesh_material_kind", kind);
    h5::write_doubles(g.id(), "submesh_magnetization", {ns, 3}, magnetization.data());
    h5::write_doubles(g.id(), "submesh_color", {ns, 3}, color.data());
  }

  // The magnetic model's cells (body frame) so field export runs from the cache alone.
  {
    Handle g = h5::create_group(f, "magnetics");
    magnetics::CellTable cells;
    magnetics::PartTable parts;
    magnetics::model_tables(model, cells, parts);
    const hsize_t nc = cells.size(), np = parts.body.size();
    Handle c = h5::create_group(g.id(), "cells");
    std::vector<std::int64_t> cb(cells.body.begin(), cells.body.end()), cp(cells.part.begin(), cells.part.end()),
        full(cells.full.begin(), cells.full.end()), ball(cells.ball.begin(), cells.ball.end());
    h5::write_ints(c.id(), "body", {nc}, cb.data());
    h5::write_ints(c.id(), "part", {nc}, cp.data());
    h5::write_doubles(c.id(), "position", {nc, 3}, flat(cells.position).data(), "m");
    h5::write_doubles(c.id(), "center", {nc, 3}, flat(cells.center).data(), "m");
    h5::write_doubles(c.id(), "half", {nc, 3}, flat(cells.half).data(), "m");
    h5::write_doubles(c.id(), "moment", {nc, 3}, flat(cells.moment).data(), "A m2");
    h5::write_doubles(c.id(), "volume", {nc}, cells.volume.data(), "m3");
    h5::write_doubles(c.id(), "chi", {nc}, cells.chi.data());
    h5::write_ints(c.id(), "full", {nc}, full.data());
    h5::write_ints(c.id(), "ball", {nc}, ball.data());
    Handle p = h5::create_group(g.id(), "parts");
    std::vector<std::int64_t> pb(parts.body.begin(), parts.body.end());
    std::vector<double> ppos, prot;
    for (const auto& pose : parts.pose) {
      ppos.insert(ppos.end(), {pose.position[0], pose.position[1], pose.position[2]});
      prot.insert(prot.end(), {pose.rotation.w(), pose.rotation.x(), pose.rotation.y(), pose.rotation.z()});
    }
    h5::write_ints(p.id(), "body", {np}, pb.data());
    h5::write_doubles(p.id(), "position", {np, 3}, ppos.data(), "m");
    h5::write_doubles(p.id(), "orientation", {np, 4}, prot.data());
    h5::write_doubles(p.id(), "magnetization", {np, 3}, flat(parts.magnetization).data(), "A m-1");
    h5::write_doubles(p.id(), "half", {np, 3}, flat(parts.half).data(), "m");
    h5::write_doubles(p.id(), "chi", {np}, parts.chi.data());
    if (!parts.surface_begin.empty()) {  // exact surfaces of permanent parts (physics.md §12)
      std::vector<std::int64_t> sb(parts.surface_begin.begin(), parts.surface_begin.end());
      h5::write_ints(p.id(), "surface_begin", {np + 1}, sb.data());
      h5::write_doubles(p.id(), "surface_vertex", {parts.surface_vertex.size(), 3}, flat(parts.surface_vertex).data(), "m");
    }
    std::vector<std::int64_t> ind(model.induced_cells.begin(), model.induced_cells.end());
    h5::write_ints(g.id(), "induced_cells", {ind.size()}, ind.data());
    m.ninduced = ind.size();
  }

  // Frame series: shared step and time (hard links in every group, as H5MD time series).
  {
    Handle frames = h5::create_group(f, "frames");
    m.step = h5::create_series(frames.id(), "step", H5T_NATIVE_INT64, {}, 256);
    m.time = h5::create_series(frames.id(), "time", H5T_NATIVE_DOUBLE, {}, 256, "s");
    Handle particles = h5::create_group(f, "particles");
    Handle bodies = h5::create_group(particles.id(), "bodies");
    auto group_with_links = [&](hid_t parent, const char* name) {
      Handle g = h5::create_group(parent, name);
      h5::check(H5Lcreate_hard(f, "/frames/step", g.id(), "step", H5P_DEFAULT, H5P_DEFAULT), "link step");
      h5::check(H5Lcreate_hard(f, "/frames/time", g.id(), "time", H5P_DEFAULT, H5P_DEFAULT), "link time");
      return g;
    };
    const hsize_t chunk = std::max<hsize_t>(1, std::min<hsize_t>(64, 65536 / std::max<std::size_t>(n, 1)));
    for (const Series& s : kBodySeries) {
      Handle g = group_with_links(bodies.id(), s.name);
      m.body_series.push_back(
          h5::create_series(g.id(), "value", H5T_NATIVE_DOUBLE, {n, hsize_t(s.components)}, chunk, s.unit));
    }
    Handle obs = h5::create_group(f, "observables");
    for (const Series& s : kObservables) {
      Handle g = group_with_links(obs.id(), s.name);
      std::vector<hsize_t> tail;
      if (s.components > 1) tail.push_back(s.components);
      m.observables.push_back(h5::create_series(g.id(), "value", H5T_NATIVE_DOUBLE, tail, 256, s.unit));
    }
    Handle mg(h5::check_id(H5Gopen2(f, "magnetics", H5P_DEFAULT), "open magnetics"));
    if (m.ninduced > 0) {
      Handle g = group_with_links(mg.id(), "induced_moment");
      const hsize_t ichunk = std::max<hsize_t>(1, std::min<hsize_t>(64, 16384 / m.ninduced));
      m.induced = h5::create_series(g.id(), "value", H5T_NATIVE_DOUBLE, {m.ninduced, 3}, ichunk, "A m2");
    }
    // Stuck joints (StuckRow), ragged: frame k's are the next stuck_count[k] rows.
    Handle contacts = h5::create_group(f, "contacts");
    m.stuck_count = h5::create_series(contacts.id(), "stuck_count", H5T_NATIVE_INT64, {}, 256);
    m.stuck = h5::create_series(contacts.id(), "stuck", H5T_NATIVE_DOUBLE, {kStuckValues}, 64);
    h5::attr_string(m.stuck.id(), "columns",
                    "a, b, normal_in_a[3], mu, lever, pivot_a[3], pivot_b[3], basis_a[9], basis_b[9], origin_a[3], "
                    "origin_b[3] (Bullet body frames of a and b, m; matrices row-major)");
    Handle bake = h5::create_group(f, "bake");
    m.frames_done = h5::create_series(bake.id(), "frames_done", H5T_NATIVE_INT64, {}, 1);
    m.status = h5::create_series(bake.id(), "status", H5T_NATIVE_INT64, {}, 1);
    h5::attr_string(m.status.id(), "codes", "0 running (or killed), 1 complete, 2 interrupted (resumable), 3 failed");
    const std::int64_t zero = 0;
    h5::write_row(m.frames_done.id(), H5T_NATIVE_INT64, 0, &zero);
    h5::write_row(m.status.id(), H5T_NATIVE_INT64, 0, &zero);
  }
  // From here on only appends: a reader (or a crash) sees a consistent file after every flush.
  h5::check(H5Fflush(f, H5F_SCOPE_GLOBAL), "flush");
  h5::check(H5Fstart_swmr_write(f), "start SWMR writing");
}

CacheWriter::~CacheWriter() {
  try {
    close();
  } catch (...) {
  }
}

void CacheWriter::append(const CacheFrame& fr, const FrameObservables& d, const std::vector<StuckRow>& stuck) {
  Impl& m = *impl_;
  const hsize_t row = frames_;
  const std::size_t n = m.scene->bodies.size();
  const bool sized = fr.position.size() == n && fr.orientation.size() == n && fr.velocity.size() == n &&
                     fr.angular_velocity.size() == n && fr.force.size() == n && fr.torque.size() == n &&
                     (fr.sleep.empty() || (fr.sleep.size() == 2 * n && fr.sleep_reference.size() == 6 * n));
  if (!sized) throw h5::Error("frame: wrong body count");
  // Body origin (scene frame), orientation (w, x, y, z), COM velocity, forces.
  std::vector<double> ori;
  for (const Quat& q : fr.orientation) ori.insert(ori.end(), {q.w(), q.x(), q.y(), q.z()});
  const std::vector<double> sleep = fr.sleep.empty() ? std::vector<double>(2 * n, 0.0) : fr.sleep;
  const std::vector<double> reference = fr.sleep.empty() ? std::vector<double>(6 * n, 0.0) : fr.sleep_reference;
  const std::vector<double> rows[] = {flat(fr.position), ori, flat(fr.velocity), flat(fr.angular_velocity), flat(fr.force),
                                      flat(fr.torque), sleep, reference};
  static_assert(std::size(rows) == std::size(kBodySeries));
  for (std::size_t k = 0; k < m.body_series.size(); ++k) {
    h5::write_row(m.body_series[k].id(), H5T_NATIVE_DOUBLE, row, rows[k].data());
  }
  const double obs[][3] = {{d.kinetic_energy},
                           {d.gravity_energy},
                           {d.magnetic_energy},
                           {d.momentum[0], d.momentum[1], d.momentum[2]},
                           {d.angular_momentum[0], d.angular_momentum[1], d.angular_momentum[2]},
                           {d.magnetics_seconds},
                           {d.rigid_seconds},
                           {d.cells_visited},
                           {d.induction_iterations},
                           {d.induction_residual},
                           {d.substeps},
                           {d.energy_drift},
                           {d.max_speed},
                           {d.max_penetration},
                           {d.sleeping},
                           {d.body_steps},
                           {d.applied_field[0], d.applied_field[1], d.applied_field[2]}};
  static_assert(std::size(obs) == std::size(kObservables));
  for (std::size_t k = 0; k < m.observables.size(); ++k) {
    h5::write_row(m.observables[k].id(), H5T_NATIVE_DOUBLE, row, obs[k]);
  }
  if (m.ninduced > 0) {
    if (fr.induced_moment.size() != m.ninduced) throw h5::Error("induced moments: wrong count");
    h5::write_row(m.induced.id(), H5T_NATIVE_DOUBLE, row, flat(fr.induced_moment).data());
  }
  std::vector<double> joints;
  for (const StuckRow& r : stuck) joints.insert(joints.end(), r.begin(), r.end());
  h5::write_rows(m.stuck.id(), H5T_NATIVE_DOUBLE, m.stuck_rows, stuck.size(), joints.data());
  m.stuck_rows += stuck.size();
  const std::int64_t nstuck = static_cast<std::int64_t>(stuck.size());
  h5::write_row(m.stuck_count.id(), H5T_NATIVE_INT64, row, &nstuck);
  const std::int64_t step = fr.frame;
  h5::write_row(m.step.id(), H5T_NATIVE_INT64, row, &step);
  h5::write_row(m.time.id(), H5T_NATIVE_DOUBLE, row, &fr.time);
  h5::check(H5Fflush(m.file.id(), H5F_SCOPE_GLOBAL), "flush frame");
  // Only now is the frame complete.
  const std::int64_t done = frames_ + 1;
  h5::write_row(m.frames_done.id(), H5T_NATIVE_INT64, 0, &done);
  h5::check(H5Fflush(m.file.id(), H5F_SCOPE_GLOBAL), "flush frame count");
  ++frames_;
}

void CacheWriter::copy_frames_from(const CacheReader& from, int count) {
  Impl& m = *impl_;
  auto copy = [&](const std::string& path, hid_t dataset, hid_t type, bool optional = false) {
    if (optional && !h5::exists(from.file(), path)) {
      // A cache from before this series: zeros (every body awake, nothing asleep), and for the
      // applied field the constant one it was baked with.
      const std::vector<hsize_t> shape = h5::shape(dataset);
      std::size_t row = 1;
      for (std::size_t k = 1; k < shape.size(); ++k) row *= shape[k];
      std::vector<double> fill(row, 0.0);
      if (path == "observables/applied_field/value") fill = from.parameter_doubles("external_field");
      for (int f = 0; f < count; ++f) h5::write_row(dataset, type, f, fill.data());
      return;
    }
    h5::Handle src(h5::check_id(H5Dopen2(from.file(), path.c_str(), H5P_DEFAULT), "open " + path));
    const std::vector<hsize_t> shape = h5::shape(src.id());
    std::size_t row = 1;
    for (std::size_t k = 1; k < shape.size(); ++k) row *= shape[k];
    for (int f = 0; f < count; ++f) {
      if (type == H5T_NATIVE_INT64) {
        const std::int64_t v = static_cast<std::int64_t>(h5::read_rows(from.file(), path, f, 1).at(0));
        h5::write_row(dataset, type, f, &v);
      } else {
        const std::vector<double> v = h5::read_rows(from.file(), path, f, 1);
        if (v.size() != row) throw h5::Error(path + ": unexpected row size");
        h5::write_row(dataset, type, f, v.data());
      }
    }
  };
  for (std::size_t k = 0; k < m.body_series.size(); ++k) {
    copy(std::string("particles/bodies/") + kBodySeries[k].name + "/value", m.body_series[k].id(), H5T_NATIVE_DOUBLE,
         k >= kRequiredBodySeries);
  }
  for (std::size_t k = 0; k < m.observables.size(); ++k) {
    copy(std::string("observables/") + kObservables[k].name + "/value", m.observables[k].id(), H5T_NATIVE_DOUBLE,
         k >= kRequiredObservables);
  }
  if (m.ninduced > 0) copy("magnetics/induced_moment/value", m.induced.id(), H5T_NATIVE_DOUBLE);
  copy("contacts/stuck_count", m.stuck_count.id(), H5T_NATIVE_INT64, true);
  m.stuck_rows = 0;
  if (!from.layout_.stuck_begin.empty()) {
    const hsize_t rows = hsize_t(from.layout_.stuck_begin.at(count));
    if (rows > 0) {
      const std::vector<double> v = h5::read_rows(from.file(), "contacts/stuck", 0, rows);
      h5::write_rows(m.stuck.id(), H5T_NATIVE_DOUBLE, 0, rows, v.data());
    }
    m.stuck_rows = rows;
  }
  copy("frames/step", m.step.id(), H5T_NATIVE_INT64);
  copy("frames/time", m.time.id(), H5T_NATIVE_DOUBLE);
  h5::check(H5Fflush(m.file.id(), H5F_SCOPE_GLOBAL), "flush");
  const std::int64_t done = count;
  h5::write_row(m.frames_done.id(), H5T_NATIVE_INT64, 0, &done);
  h5::check(H5Fflush(m.file.id(), H5F_SCOPE_GLOBAL), "flush frame count");
  frames_ = count;
}

void CacheWriter::set_status(BakeStatus status) {
  const std::int64_t v = static_cast<int>(status);
  h5::write_row(impl_->status.id(), H5T_NATIVE_INT64, 0, &v);
  h5::check(H5Fflush(impl_->file.id(), H5F_SCOPE_GLOBAL), "flush status");
}

void CacheWriter::close() {
  if (!impl_ || !impl_->file) return;
  impl_->body_series.clear();
  impl_->observables.clear();
  impl_->step.reset(), impl_->time.reset(), impl_->induced.reset(), impl_->frames_done.reset(), impl_->status.reset();
  impl_->stuck_count.reset(), impl_->stuck.reset();
  // Closed once, by hand, so a failure (disk full) is reported; the handle never closes it again.
  const herr_t st = H5Fclose(impl_->file.release());
  h5::check(st, "close cache");
}

// ---------------------------------------------------------------------------------------------
struct CacheReader::Impl {
  Handle file;
};

CacheReader::CacheReader(const std::string& path) : path_(path), impl_(std::make_unique<Impl>()) {
  h5::quiet();
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": no such file");
  if (H5Fis_hdf5(path.c_str()) <= 0) throw std::runtime_error(path + ": not an HDF5 file");
  // A bake killed while writing leaves the SWMR-writer flag set: open it as a SWMR reader.
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) {
    Handle fapl(H5Pcreate(H5P_FILE_ACCESS));
    H5Pset_libver_bounds(fapl.id(), H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);
    // A SWMR reader retries a metadata read whose checksum fails 100 times with growing sleeps
    // (HDF5's default, for racing a live writer): a corrupt file then hangs for minutes (found
    // by fuzz/cache_fuzzer). Our caches are read after their writer flushed: a few attempts.
    H5Pset_metadata_read_attempts(fapl.id(), 4);
    f = H5Fopen(path.c_str(), H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, fapl.id());
  }
  if (f < 0) throw std::runtime_error(path + ": cannot open as HDF5 (corrupt or truncated?)");
  impl_->file = Handle(f);
  try {
    if (H5Aexists(f, "format") <= 0 || h5::read_attr_string(f, "format") != kFormat) {
      throw std::runtime_error("not a magbake cache (no format = \"magbake-cache\" attribute)");
    }
    const std::vector<std::int64_t> done = h5::read_ints(f, "bake/frames_done");
    const std::vector<std::int64_t> status = h5::read_ints(f, "bake/status");
    if (done.empty() || status.empty()) throw std::runtime_error("/bake/frames_done or /bake/status is empty");
    if (status[0] < 0 || status[0] > 3) throw std::runtime_error("unknown /bake/status " + std::to_string(status[0]));
    status_ = static_cast<BakeStatus>(status[0]);
    // Every dataset the readers use, with its shape, index ranges and finite constants; never
    // more frames than every series holds.
    layout_ = check_cache_layout(f, done[0]);
    frames_ = layout_.frames;
    Handle p(h5::check_id(H5Gopen2(f, "parameters", H5P_DEFAULT), "parameters"));
    fps_ = h5::read_attr_doubles(p.id(), "fps").at(0);
    first_frame_ = static_cast<int>(h5::read_attr_doubles(p.id(), "first_frame").at(0));
    names_ = h5::read_strings(f, "bodies/name");
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

CacheReader::~CacheReader() = default;

hid_t CacheReader::file() const { return impl_->file.id(); }

std::string CacheReader::scene_text() const { return h5::read_strings(file(), "parameters/scene_text").at(0); }
std::string CacheReader::scene_hash() const { return attribute("scene_hash"); }

std::string CacheReader::attribute(const std::string& name) const {
  Handle p(h5::check_id(H5Gopen2(file(), "parameters", H5P_DEFAULT), "parameters"));
  return h5::read_attr_string(p.id(), name);
}

std::vector<double> CacheReader::parameter_doubles(const std::string& name) const {
  Handle p(h5::check_id(H5Gopen2(file(), "parameters", H5P_DEFAULT), "parameters"));
  return h5::read_attr_doubles(p.id(), name);
}

std::vector<CacheReader::BodyInfo> CacheReader::body_info() const {
  const std::vector<double> mass = h5::read_doubles(file(), "bodies/mass");  // shape checked at open
  std::vector<BodyInfo> out(names_.size());
  for (std::size_t i = 0; i < out.size() && i < mass.size(); ++i) out[i].mass = mass[i];
  for (const char* key : {"motion", "material"}) {
    const std::string path = std::string("bodies/") + key;
    if (!h5::exists(file(), path)) continue;
    std::vector<std::string> v;
    try {
      v = h5::read_strings(file(), path);
    } catch (const std::exception&) {
      continue;
    }
    if (v.size() != out.size()) continue;
    for (std::size_t i = 0; i < out.size(); ++i) (key[1] == 'o' ? out[i].motion : out[i].material) = v[i];
  }
  return out;
}

std::vector<Vec3> CacheReader::centers_of_mass() const {
  const std::vector<double> c = h5::read_doubles(file(), "bodies/center_of_mass");
  std::vector<Vec3> out;
  for (std::size_t i = 0; i + 2 < c.size(); i += 3) out.emplace_back(c[i], c[i + 1], c[i + 2]);
  return out;
}

CacheFrame CacheReader::frame(int index) const {
  if (index < 0 || index >= frames_) throw std::runtime_error(path_ + ": frame index out of range");
  CacheFrame fr;
  const hid_t f = file();
  fr.frame = static_cast<int>(h5::read_rows(f, "frames/step", index, 1).at(0));
  fr.time = h5::read_rows(f, "frames/time", index, 1).at(0);
  auto vecs = [&](const char* name) {
    const std::vector<double> v = h5::read_rows(f, std::string("particles/bodies/") + name + "/value", index, 1);
    std::vector<Vec3> out;
    for (std::size_t i = 0; i + 2 < v.size(); i += 3) out.emplace_back(v[i], v[i + 1], v[i + 2]);
    return out;
  };
  fr.position = vecs("position");
  fr.velocity = vecs("velocity");
  fr.angular_velocity = vecs("angular_velocity");
  fr.force = vecs("magnetic_force");
  fr.torque = vecs("magnetic_torque");
  const std::vector<double> q = h5::read_rows(f, "particles/bodies/orientation/value", index, 1);
  for (std::size_t i = 0; i + 3 < q.size(); i += 4) fr.orientation.emplace_back(q[i], q[i + 1], q[i + 2], q[i + 3]);
  if (layout_.sleep) {
    fr.sleep = h5::read_rows(f, "particles/bodies/sleep/value", index, 1);
    fr.sleep_reference = h5::read_rows(f, "particles/bodies/sleep_reference/value", index, 1);
  }
  fr.applied_field = applied_field(index);
  if (layout_.induced > 0) {
    const std::vector<double> v = h5::read_rows(f, "magnetics/induced_moment/value", index, 1);
    for (std::size_t i = 0; i + 2 < v.size(); i += 3) fr.induced_moment.emplace_back(v[i], v[i + 1], v[i + 2]);
  } else {
    fr.induced_moment.clear();
  }
  // A frame that readers would turn into nonsense (NaN poses, a zero quaternion) is refused.
  auto bad = [&](const std::string& what, std::size_t i) {
    return std::runtime_error(path_ + ": frame " + std::to_string(fr.frame) + " holds a non-finite or invalid " + what +
                              (i < names_.size() ? " of body '" + names_[i] + "'" : " (row " + std::to_string(i) + ")"));
  };
  if (!std::isfinite(fr.time)) throw bad("time", names_.size());
  for (std::size_t i = 0; i < fr.position.size(); ++i) {
    if (!fr.position[i].allFinite()) throw bad("position", i);
    if (!fr.orientation[i].coeffs().allFinite() || fr.orientation[i].squaredNorm() < 1e-12) throw bad("orientation", i);
    if (!fr.velocity[i].allFinite() || !fr.angular_velocity[i].allFinite()) throw bad("velocity", i);
    if (!fr.force[i].allFinite() || !fr.torque[i].allFinite()) throw bad("force or torque", i);
  }
  for (std::size_t k = 0; k < fr.induced_moment.size(); ++k) {
    if (!fr.induced_moment[k].allFinite()) throw bad("induced moment", names_.size() + k);
  }
  return fr;
}

double CacheReader::observable_at(const std::string& name, int index) const {
  if (index < 0 || index >= frames_) throw std::runtime_error(path_ + ": frame index out of range");
  const std::string path = "observables/" + name + "/value";
  if (!h5::exists(file(), path)) throw std::runtime_error(path_ + ": holds no observable '" + name + "'");
  const double v = h5::read_rows(file(), path, index, 1).at(0);
  if (!std::isfinite(v)) {
    throw std::runtime_error(path_ + ": frame index " + std::to_string(index) + " holds a non-finite " + name);
  }
  return v;
}

std::vector<StuckRow> CacheReader::stuck_rows(int index) const {
  if (index < 0 || index >= frames_) throw std::runtime_error(path_ + ": frame index out of range");
  std::vector<StuckRow> out;
  if (layout_.stuck_begin.empty()) return out;
  const std::int64_t begin = layout_.stuck_begin[index], end = layout_.stuck_begin[index + 1];
  const std::vector<double> rows =
      end > begin ? h5::read_rows(file(), "contacts/stuck", hsize_t(begin), hsize_t(end - begin)) : std::vector<double>{};
  const double n = double(names_.size());
  for (std::int64_t r = 0; r < end - begin; ++r) {
    StuckRow row;
    std::copy_n(rows.data() + r * kStuckValues, kStuckValues, row.begin());
    bool ok = row[0] >= 0 && row[0] < row[1] && row[1] < n && row[0] == std::floor(row[0]) && row[1] == std::floor(row[1]);
    for (std::size_t k = 2; k < kStuckValues; ++k) ok = ok && std::isfinite(row[k]);
    ok = ok && (out.empty() || std::make_pair(out.back()[0], out.back()[1]) < std::make_pair(row[0], row[1]));
    if (!ok) {
      throw std::runtime_error(path_ + ": frame index " + std::to_string(index) + " holds an invalid stuck joint (row " +
                               std::to_string(begin + r) + " of /contacts/stuck)");
    }
    out.push_back(row);
  }
  return out;
}

RenderGeometry CacheReader::geometry() const {
  const hid_t f = file();
  RenderGeometry g;
  const std::vector<double> v = h5::read_doubles(f, "geometry/vertices");
  for (std::size_t i = 0; i + 2 < v.size(); i += 3) g.vertices.emplace_back(v[i], v[i + 1], v[i + 2]);
  const std::vector<std::int64_t> t = h5::read_ints(f, "geometry/triangles");
  for (std::size_t i = 0; i + 2 < t.size(); i += 3) g.triangles.push_back({t[i], t[i + 1], t[i + 2]});
  const auto body = h5::read_ints(f, "geometry/submesh_body");
  const auto vb = h5::read_ints(f, "geometry/submesh_vertex_begin"), vc = h5::read_ints(f, "geometry/submesh_vertex_count");
  const auto tb = h5::read_ints(f, "geometry/submesh_triangle_begin"), tc = h5::read_ints(f, "geometry/submesh_triangle_count");
  const auto role = h5::read_strings(f, "geometry/submesh_role");
  const auto kind = h5::read_strings(f, "geometry/submesh_material_kind");
  const auto mag = h5::read_doubles(f, "geometry/submesh_magnetization");
  const auto col = h5::exists(f, "geometry/submesh_color") ? h5::read_doubles(f, "geometry/submesh_color")
                                                           : std::vector<double>();
  for (std::size_t s = 0; s < body.size(); ++s) {
    g.submeshes.push_back(RenderGeometry::Submesh{static_cast<int>(body[s]), vb[s], vc[s], tb[s], tc[s], role[s], kind[s],
                                                  Vec3(mag[3 * s], mag[3 * s + 1], mag[3 * s + 2]), std::nullopt});
    if (!col.empty() && col[3 * s] >= 0) g.submeshes.back().color = Vec3(col[3 * s], col[3 * s + 1], col[3 * s + 2]);
  }
  return g;
}

Vec3 CacheReader::applied_field(int index) const {
  const std::string path = "observables/applied_field/value";
  if (!h5::exists(file(), path)) {
    const std::vector<double> ext = parameter_doubles("external_field");
    return Vec3(ext.at(0), ext.at(1), ext.at(2));
  }
  h5::Handle d(h5::check_id(H5Dopen2(file(), path.c_str(), H5P_DEFAULT), "open " + path));
  const std::vector<hsize_t> shape = h5::shape(d.id());
  if (shape.size() != 2 || shape[1] != 3 || index < 0 || shape[0] <= hsize_t(index)) {
    throw h5::Error(path_ + ": /" + path + " does not hold frame " + std::to_string(index) + " as 3 numbers");
  }
  const std::vector<double> v = h5::read_rows(file(), path, index, 1);
  const Vec3 b(v.at(0), v.at(1), v.at(2));
  if (!b.allFinite()) throw h5::Error(path_ + ": /" + path + " holds a non-finite value at frame " + std::to_string(index));
  return b;
}

std::vector<double> CacheReader::observable(const std::string& name) const {
  const std::string path = "observables/" + name + "/value";
  if (frames_ == 0 || !h5::exists(file(), path)) return {};
  h5::Handle d(h5::check_id(H5Dopen2(file(), path.c_str(), H5P_DEFAULT), "open " + path));
  const std::vector<hsize_t> shape = h5::shape(d.id());
  if (shape.size() != 1 || shape[0] < hsize_t(frames_)) return {};
  return h5::read_rows(file(), path, 0, frames_);
}

magnetics::Model CacheReader::model(std::vector<int>* induced_order) const {
  const hid_t f = file();
  magnetics::CellTable cells;
  magnetics::PartTable parts;
  auto v3 = [](const std::vector<double>& v) {
    std::vector<Vec3> out;
    for (std::size_t i = 0; i + 2 < v.size(); i += 3) out.emplace_back(v[i], v[i + 1], v[i + 2]);
    return out;
  };
  for (auto x : h5::read_ints(f, "magnetics/cells/body")) cells.body.push_back(int(x));
  for (auto x : h5::read_ints(f, "magnetics/cells/part")) cells.part.push_back(int(x));
  for (auto x : h5::read_ints(f, "magnetics/cells/full")) cells.full.push_back(std::uint8_t(x));
  if (h5::exists(f, "magnetics/cells/ball")) {  // absent in caches written before exact balls
    for (auto x : h5::read_ints(f, "magnetics/cells/ball")) cells.ball.push_back(std::uint8_t(x));
  }
  cells.position = v3(h5::read_doubles(f, "magnetics/cells/position"));
  cells.center = v3(h5::read_doubles(f, "magnetics/cells/center"));
  cells.half = v3(h5::read_doubles(f, "magnetics/cells/half"));
  cells.moment = v3(h5::read_doubles(f, "magnetics/cells/moment"));
  cells.volume = h5::read_doubles(f, "magnetics/cells/volume");
  cells.chi = h5::read_doubles(f, "magnetics/cells/chi");
  for (auto x : h5::read_ints(f, "magnetics/parts/body")) parts.body.push_back(int(x));
  const auto pp = v3(h5::read_doubles(f, "magnetics/parts/position"));
  const auto pr = h5::read_doubles(f, "magnetics/parts/orientation");
  for (std::size_t i = 0; i < pp.size(); ++i) {
    parts.pose.push_back(magnetics::Pose{Quat(pr[4 * i], pr[4 * i + 1], pr[4 * i + 2], pr[4 * i + 3]), pp[i]});
  }
  parts.magnetization = v3(h5::read_doubles(f, "magnetics/parts/magnetization"));
  parts.half = v3(h5::read_doubles(f, "magnetics/parts/half"));
  parts.chi = h5::read_doubles(f, "magnetics/parts/chi");
  if (h5::exists(f, "magnetics/parts/surface_begin")) {  // absent in caches written before surfaces
    for (auto x : h5::read_ints(f, "magnetics/parts/surface_begin")) parts.surface_begin.push_back(int(x));
    parts.surface_vertex = v3(h5::read_doubles(f, "magnetics/parts/surface_vertex"));
  }
  std::vector<int> order;
  magnetics::Model m = magnetics::model_from_cells(static_cast<int>(names_.size()), cells, parts, 32, &order);
  if (induced_order) {
    const std::vector<std::int64_t> stored = h5::read_ints(f, "magnetics/induced_cells");
    std::vector<int> rank_of(cells.size(), -1);
    for (std::size_t r = 0; r < stored.size(); ++r) rank_of[stored[r]] = static_cast<int>(r);
    induced_order->clear();
    for (int c : m.induced_cells) induced_order->push_back(rank_of[order[c]]);
  }
  return m;
}

}  // namespace magbake::io
