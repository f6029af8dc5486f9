#include "cli.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>
#include <sstream>

namespace magbake::cli {

std::optional<scene::Scene> load_or_report(const std::string& path) {
  try {
    return scene::load_scene(path);
  } catch (const scene::SceneError& e) {
    std::cerr << e.diagnostics().format();
    std::cerr << "magbake: " << e.diagnostics().items().size() << " problem(s) in " << path << "; nothing written\n";
    return std::nullopt;
  }
}

nlohmann::json json_vec(const Eigen::Vector3d& v) { return nlohmann::json::array({v[0], v[1], v[2]}); }

void print_json(const nlohmann::json& j) { std::cout << j.dump(2) << '\n' << std::flush; }

namespace {
const char* motion_name(scene::Motion m) {
  switch (m) {
    case scene::Motion::kDynamic: return "dynamic";
    case scene::Motion::kStatic: return "static";
    case scene::Motion::kKinematic: return "kinematic";
  }
  return "?";
}
}  // namespace

std::string scene_summary(const scene::Scene& s, bool all_bodies) {
  std::ostringstream os;
  char buf[512];
  os << "scene    " << s.name << "  (" << s.file << ", sha256 " << s.hash.substr(0, 12) << ")\n";
  std::snprintf(buf, sizeof buf, "units    length %s, angle %s (everything below in SI)\n", s.length_unit.c_str(),
                s.angle_unit.c_str());
  os << buf;
  const int frames = s.last_frame - s.first_frame + 1;
  const double duration = (s.last_frame - s.first_frame) / s.fps;
  std::snprintf(buf, sizeof buf, "time     %g fps, frames %d-%d (%d frames, %.3g s), substep %.4g ms (%.0f substeps)\n",
                s.fps, s.first_frame, s.last_frame, frames, duration, s.dt * 1e3,
                static_cast<double>(s.steps_per_frame()) * (frames - 1));
  os << buf;
  std::snprintf(buf, sizeof buf, "gravity  %g %g %g m/s²\n", s.gravity[0], s.gravity[1], s.gravity[2]);
  os << buf;
  const auto& m = s.magnetics;
  std::snprintf(buf, sizeof buf,
                "magnetics quality %s: cell size %s, theta %g, near field %g cells (order %d), induction %s "
                "(tolerance %g), applied field %g %g %g T\n",
                m.quality.c_str(),
                m.cell_size ? (std::to_string(*m.cell_size * 1e3) + " mm").c_str()
                            : ("extent/" + std::to_string(m.cells_per_extent) + " (soft parts extent/" +
                               std::to_string(m.soft_cells_per_extent) + ")")
                                  .c_str(),
                m.theta, m.near_field, m.near_field_order, m.induction.c_str(), m.induction_tolerance, m.external_field[0],
                m.external_field[1], m.external_field[2]);
  os << buf;
  if (s.applied_field_animated()) {
    os << "          the applied field above is at t = 0; it is " << (m.rotating_field ? "rotating" : "keyed") << " (animated)\n";
  }
  os << "materials";
  for (const auto& mt : s.materials) {
    os << "  " << mt.name << " (" << mt.kind_name;
    if (mt.kind == magnetics::MaterialKind::kPermanent) os << ", " << mt.remanence << " T";
    if (mt.kind == magnetics::MaterialKind::kLinear) os << ", chi " << mt.chi;
    if (mt.saturation > 0) os << ", saturates at " << mt.saturation << " T";
    os << ")";
  }
  os << "\nbodies   " << s.bodies.size() << "\n";
  std::snprintf(buf, sizeof buf, "  %-16s %-30s %-12s %-10s %10s\n", "name", "shape", "material", "motion", "mass (g)");
  os << buf;
  const std::size_t shown = all_bodies || s.bodies.size() <= kSummaryBodies ? s.bodies.size() : kSummaryBodies - 4;
  for (std::size_t i = 0; i < shown; ++i) {
    const scene::Body& b = s.bodies[i];
    std::string mat = b.material >= 0 ? s.materials[b.material].name : "-";
    if (!b.parts.empty()) {
      mat.append("+").append(std::to_string(b.parts.size())).append(b.parts.size() == 1 ? " part" : " parts");
    }
    std::snprintf(buf, sizeof buf, "  %-16s %-30s %-12s %-10s %10.4g\n", b.name.c_str(), b.shape.describe().c_str(),
                  mat.c_str(), motion_name(b.motion), b.mass * 1e3);
    os << buf;
  }
  if (shown < s.bodies.size()) os << "  ... and " << s.bodies.size() - shown << " more (--verbose lists every body)\n";
  if (!s.joints.empty()) {
    os << "joints   " << s.joints.size() << ":";
    for (const scene::Joint& j : s.joints) {
      os << "  " << j.name << " (" << j.type_name << " " << s.bodies[j.a].name << "-"
         << (j.b >= 0 ? s.bodies[j.b].name : std::string("world")) << ")";
    }
    os << "\n";
  }
  os << "outputs  cache " << (s.cache ? *s.cache : "(none)");
  if (s.field) os << "; field " << s.field->path;
  if (s.preview) os << "; preview " << s.preview->path << " " << s.preview->width << "x" << s.preview->height;
  os << "\n";
  return os.str();
}

nlohmann::json scene_summary_json(const scene::Scene& s) {
  using nlohmann::json;
  json j;
  j["scene"] = s.file;
  j["name"] = s.name;
  j["sha256"] = s.hash;
  j["units"] = {{"length", s.length_unit}, {"angle", s.angle_unit}};
  const int frames = s.last_frame - s.first_frame + 1;
  j["time"] = {{"fps", s.fps},
               {"frames", {s.first_frame, s.last_frame}},
               {"frame_count", frames},
               {"duration_seconds", (s.last_frame - s.first_frame) / s.fps},
               {"dt_seconds", s.dt},
               {"substeps", static_cast<long long>(s.steps_per_frame()) * (frames - 1)},
               {"sleep_seconds", s.sleep_time}};
  j["gravity"] = json_vec(s.gravity);
  const auto& m = s.magnetics;
  json mg = {{"quality", m.quality},
             {"theta", m.theta},
             {"near_field_cells", m.near_field},
             {"near_field_order", m.near_field_order},
             {"induction", m.induction},
             {"induction_tolerance", m.induction_tolerance},
             {"external_field_T", json_vec(m.external_field)},  // at t = 0
             {"external_field_animated", s.applied_field_animated()}};
  if (m.cell_size) {
    mg["cell_size_m"] = *m.cell_size;
  } else {
    mg["cells_across"] = m.cells_per_extent;
    mg["soft_cells_across"] = m.soft_cells_per_extent;
  }
  j["magnetics"] = mg;
  auto damping = [](double linear, double angular) { return json{{"linear", linear}, {"angular", angular}}; };
  j["materials"] = json::array();
  for (const auto& mt : s.materials) {
    json o = {{"name", mt.name}, {"kind", mt.kind_name}};
    if (mt.kind == magnetics::MaterialKind::kPermanent) o["remanence_T"] = mt.remanence;
    if (mt.kind == magnetics::MaterialKind::kLinear || mt.kind == magnetics::MaterialKind::kSuperconductor) o["chi"] = mt.chi;
    if (mt.saturation > 0) o["saturation_T"] = mt.saturation;
    if (mt.density) o["density"] = *mt.density;
    if (mt.friction) o["friction"] = *mt.friction;
    if (mt.restitution) o["restitution"] = *mt.restitution;
    if (mt.linear_damping || mt.angular_damping) {
      o["damping"] = damping(mt.linear_damping.value_or(0), mt.angular_damping.value_or(0));
    }
    if (mt.color) o["color"] = json_vec(*mt.color);
    j["materials"].push_back(o);
  }
  j["bodies"] = json::array();
  for (const scene::Body& b : s.bodies) {
    json o = {{"name", b.name},
              {"shape", b.shape.describe()},
              {"material", b.material >= 0 ? json(s.materials[b.material].name) : json(nullptr)},
              {"parts", b.parts.size()},
              {"motion", motion_name(b.motion)},
              {"mass_kg", b.mass},
              {"friction", b.friction},
              {"restitution", b.restitution},
              {"damping", damping(b.linear_damping, b.angular_damping)}};
    if (b.color) o["color"] = json_vec(*b.color);
    j["bodies"].push_back(o);
  }
  j["joints"] = json::array();
  for (const scene::Joint& jt : s.joints) {
    json o = {{"name", jt.name},
              {"type", jt.type_name},
              {"bodies", {s.bodies[jt.a].name, jt.b >= 0 ? s.bodies[jt.b].name : std::string("world")}}};
    if (jt.limits) o["limits"] = {jt.limits->first, jt.limits->second};
    j["joints"].push_back(o);
  }
  json out = {{"cache", s.cache ? json(*s.cache) : json(nullptr)}, {"usd", s.usd ? json(*s.usd) : json(nullptr)}};
  out["field"] = s.field ? json(s.field->path) : json(nullptr);
  out["preview"] = s.preview ? json(s.preview->path) : json(nullptr);
  j["outputs"] = out;
  return j;
}

}  // namespace magbake::cli
