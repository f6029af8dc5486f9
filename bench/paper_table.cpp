// paper_table: the paper's Table 1 for one scene of scenes/paper, measured on states of a baked
// shot (bench/run_paper_table.sh bakes the shots and runs this for every scene).
//
//   paper_table SCENE.yaml CACHE.h5 OUT_DIR --label TST --window F:N --instants F1,F2
//               [--threads 1,2] [--gain-frames 3] [--max-ref-cells N]
//
// 1. Timing: restores the cached state at frame F and advances N frames with the scene's own
//    settings, once per thread count; per 1 ms of simulated time: T_mag, T_rbd, substeps, and per
//    magnetics evaluation: induction iterations, cells, cell/node/near pairs.
// 2. Gain (the paper's): time of one evaluation with every finest cell pair (theta 0) over the
//    adaptive one, at frames spread over the window (1 thread, warm-started from the cache).
// 3. Run time against error: at each instant (a cached frame where bodies touch or nearly touch),
//    the force on every body with a significant force (|F| >= 1% of the largest) for presets and
//    explicit resolution/theta settings, against a reference refined until the largest force
//    changes by less than 0.5% between two successive refinements.
// Writes OUT_DIR/<label>.json (timing, gain, reference convergence) and
// OUT_DIR/<label>_time_vs_error.csv.
#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cache_state.h"
#include "io/cache.h"
#include "magnetics/system.h"
#include "scene/load.h"
#include "scene/scene_magnetics.h"
#include "sim/simulator.h"

namespace {

using namespace magbake;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;
using magnetics::Vec3;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::vector<int> parse_ints(const std::string& s) {
  std::vector<int> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(std::stoi(item));
  return out;
}

struct Args {
  std::string scene, cache, out, label;
  int window_frame = 0, window_frames = 3;
  std::vector<int> instants;
  std::vector<int> threads{1, 0};
  int gain_frames = 3;
  long long max_ref_cells = 400000;
  std::string parts = "timing,gain,error";  ///< which measurements to run (results merge into the JSON)
  bool wants(const std::string& part) const { return ("," + parts + ",").find("," + part + ",") != std::string::npos; }
};

Args parse_args(int argc, char** argv) {
  Args a;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto val = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(k + " needs a value");
      return argv[++i];
    };
    if (k == "--label") a.label = val();
    else if (k == "--window") {
      const std::string w = val();
      const auto c = w.find(':');
      if (c == std::string::npos) throw std::runtime_error("--window expects FRAME:COUNT");
      a.window_frame = std::stoi(w.substr(0, c));
      a.window_frames = std::stoi(w.substr(c + 1));
    } else if (k == "--instants") a.instants = parse_ints(val());
    else if (k == "--threads") a.threads = parse_ints(val());
    else if (k == "--gain-frames") a.gain_frames = std::stoi(val());
    else if (k == "--max-ref-cells") a.max_ref_cells = std::stoll(val());
    else if (k == "--parts") a.parts = val();
    else if (k.rfind("--", 0) == 0) throw std::runtime_error("unknown option " + k);
    else pos.push_back(k);
  }
  if (pos.size() != 3 || a.label.empty()) {
    throw std::runtime_error(
        "usage: paper_table SCENE.yaml CACHE.h5 OUT_DIR --label NAME --window F:N --instants F1,F2 "
        "[--threads 1,0] [--gain-frames 3] [--max-ref-cells N] [--parts timing,gain,error]");
  }
  a.scene = pos[0], a.cache = pos[1], a.out = pos[2];
  return a;
}

int hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

/// Index of a frame number in the cache; throws if it was not baked.
int frame_index(const io::CacheReader& cache, int frame) {
  const int k = frame - cache.first_frame();
  if (k < 0 || k >= cache.frame_count()) {
    throw std::runtime_error("frame " + std::to_string(frame) + " is not in " + cache.path() + " (frames " +
                             std::to_string(cache.first_frame()) + "-" +
                             std::to_string(cache.first_frame() + cache.frame_count() - 1) + ")");
  }
  return k;
}

/// Body poses (centre-of-mass frames) of a simulation state.
std::vector<magnetics::Pose> poses_of(const sim::SimState& s) {
  std::vector<magnetics::Pose> p(s.com_position.size());
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = magnetics::Pose{s.orientation[i], s.com_position[i]};
  return p;
}

// ---------------------------------------------------------------------------------------------
// 1. Timing of the scene's own step over a window of frames.
json time_window(const scene::Scene& sc, const magnetics::Model& model, const io::CacheReader& cache, const Args& a,
                 int threads) {
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
  sim::Simulator sim(sc, model);
  const int k = frame_index(cache, a.window_frame);
  sim.restore(cli::resume_state(cache, k, sc), a.window_frame);
  sim::FrameDiagnostics sum;
  const auto t0 = Clock::now();
  int frames = 0;
  for (; frames < a.window_frames && sim.frame() < sc.last_frame; ++frames) {
    const sim::FrameDiagnostics d = sim.advance_frame();
    sum.magnetics_seconds += d.magnetics_seconds;
    sum.rigid_seconds += d.rigid_seconds;
    sum.substeps += d.substeps;
    sum.induction_iterations += d.induction_iterations;
    sum.induction_residual = std::max(sum.induction_residual, d.induction_residual);
    sum.cell_pairs += d.cell_pairs;
    sum.node_pairs += d.node_pairs;
    sum.near_pairs += d.near_pairs;
    sum.evaluations += d.evaluations;
  }
  const double wall = seconds_since(t0);
  const double sim_ms = 1e3 * frames / sc.fps;
  const double ev = std::max(1, sum.evaluations);
  json j;
  j["threads"] = threads;
  j["frames"] = frames;
  j["simulated_ms"] = sim_ms;
  j["wall_s"] = wall;
  j["t_mag_ms_per_ms"] = 1e3 * sum.magnetics_seconds / sim_ms;
  j["t_rbd_ms_per_ms"] = 1e3 * sum.rigid_seconds / sim_ms;
  j["t_tot_ms_per_ms"] = 1e3 * wall / sim_ms;
  j["substeps_per_ms"] = sum.substeps / sim_ms;
  j["nominal_substeps_per_ms"] = 1e-3 / sc.dt;
  j["evaluations"] = sum.evaluations;
  j["induction_iterations_per_eval"] = sum.induction_iterations / ev;
  j["induction_residual_max"] = sum.induction_residual;
  j["cell_pairs_per_eval"] = sum.cell_pairs / ev;
  j["node_pairs_per_eval"] = sum.node_pairs / ev;
  j["near_pairs_per_eval"] = sum.near_pairs / ev;
  j["t_mag_ms_per_eval"] = 1e3 * sum.magnetics_seconds / ev;
  return j;
}

// ---------------------------------------------------------------------------------------------
// 2. The paper's Gain: every finest cell pair against the adaptive traversal.
struct Timed {
  double seconds = 0;
  magnetics::Result result;
};

/// Median wall time of up to `repeats` evaluations (fewer once 2 s have been spent), each on a
/// fresh State (no cached near-field tensors) warm-started with `induced` (empty: cold start
/// from zero moments).
Timed time_evaluate(const magnetics::Model& model, const magnetics::Settings& st,
                    const std::vector<magnetics::Pose>& poses, const std::vector<Vec3>& induced, int repeats) {
  std::vector<double> t;
  Timed out;
  for (int r = 0; r < repeats; ++r) {
    magnetics::State s;
    s.resize(model);
    s.body_pose = poses;
    if (induced.size() == s.induced_moment.size()) s.induced_moment = induced;
    const auto t0 = Clock::now();
    magnetics::evaluate(model, st, s, out.result);
    t.push_back(seconds_since(t0));
    double spent = 0;
    for (double x : t) spent += x;
    if (spent > 2.0) break;
  }
  out.seconds = median(t);
  return out;
}

json measure_gain(const scene::Scene& sc, const magnetics::Model& model, const io::CacheReader& cache, const Args& a) {
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
  const magnetics::Settings adaptive = scene::magnetics_settings(sc);
  magnetics::Settings all_pairs = adaptive;
  all_pairs.theta = 0;
  json rows = json::array();
  std::vector<double> gains;
  const int last = std::min(sc.last_frame, a.window_frame + a.window_frames);
  for (int g = 0; g < a.gain_frames; ++g) {
    const int f = a.window_frame + (a.gain_frames == 1 ? 0 : (last - a.window_frame) * g / (a.gain_frames - 1));
    const sim::SimState s = cli::resume_state(cache, frame_index(cache, f), sc);
    const auto poses = poses_of(s);
    const Timed ad = time_evaluate(model, adaptive, poses, s.induced_moment, 3);
    const Timed all = time_evaluate(model, all_pairs, poses, s.induced_moment, 1);
    const double gain = all.seconds / ad.seconds;
    gains.push_back(gain);
    rows.push_back({{"frame", f},
                    {"adaptive_ms", 1e3 * ad.seconds},
                    {"all_pairs_ms", 1e3 * all.seconds},
                    {"gain", gain},
                    {"adaptive_pairs", ad.result.stats.cell_pairs + ad.result.stats.node_pairs},
                    {"all_pairs", all.result.stats.cell_pairs + all.result.stats.node_pairs}});
  }
  return {{"frames", rows}, {"median_gain", gains.empty() ? 0.0 : median(gains)}};
}

// ---------------------------------------------------------------------------------------------
// 3. Run time against error.

/// A setting of the accuracy knobs, applied to a copy of the scene.
struct Knobs {
  std::string label;
  std::string quality = "default";  ///< preset applied first
  double resolution = 1;            ///< cells per length relative to the preset (cell_size / f)
  std::optional<double> theta;      ///< overrides the preset's
  std::optional<double> near_field;
  std::optional<int> near_field_order;
  std::optional<double> induction_tolerance;  ///< overrides the caller's tolerance
};

Knobs knob(std::string label, std::string quality, double resolution = 1, std::optional<double> theta = {},
           std::optional<double> near_field = {}, std::optional<int> near_field_order = {}) {
  return Knobs{std::move(label), std::move(quality), resolution, theta, near_field, near_field_order, std::nullopt};
}

/// The default preset with another induction tolerance (relative GMRES residual).
Knobs tolerance_knob(std::string label, double tolerance) {
  Knobs k = knob(std::move(label), "default");
  k.induction_tolerance = tolerance;
  return k;
}

scene::Scene with_knobs(const scene::Scene& base, const Knobs& k) {
  scene::Scene sc = base;
  scene::MagneticsSettings& mg = sc.magnetics;
  const std::optional<double> cell = mg.cell_size;
  if (!scene::apply_quality_preset(k.quality, mg)) throw std::runtime_error("unknown preset " + k.quality);
  if (cell) {
    mg.cell_size = *cell / k.resolution;
  } else {
    // Soft parts scale with the rest (the preset has replaced a scene's soft_cells_across pin:
    // the error columns measure the presets as users get them).
    mg.cells_per_extent = std::max(1, static_cast<int>(std::lround(mg.cells_per_extent * k.resolution)));
    mg.soft_cells_per_extent = std::max(1, static_cast<int>(std::lround(mg.soft_cells_per_extent * k.resolution)));
  }
  if (k.theta) mg.theta = *k.theta;
  if (k.near_field) mg.near_field = *k.near_field;
  if (k.near_field_order) mg.near_field_order = *k.near_field_order;
  return sc;
}

struct Evaluated {
  Knobs knobs;
  int cells = 0;
  double seconds = 0;  ///< per evaluation, 1 thread, cold start
  magnetics::Result result;
};

Evaluated evaluate_knobs(const scene::Scene& base, const Knobs& k, const std::vector<magnetics::Pose>& poses,
                         int threads, int repeats, std::optional<double> tolerance) {
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
  const scene::Scene sc = with_knobs(base, k);
  const magnetics::Model model = scene::build_magnetics_model(sc);
  magnetics::Settings st = scene::magnetics_settings(sc);
  // The knob's tolerance, else the caller's (references), else the preset's.
  if (k.induction_tolerance) st.induction_tolerance = *k.induction_tolerance;
  else if (tolerance) st.induction_tolerance = *tolerance;
  if (st.induction_tolerance < 1e-8) {
    // References: long Krylov cycles. GMRES(50) stalls on clusters of touching high-chi bodies
    // at fine resolution (BowlSpheres: residual 9e-4 after 1000 iterations).
    st.induction_restart = 300;
    st.induction_max_iterations = 3000;
  }
  Evaluated e;
  e.knobs = k;
  e.cells = model.cell_count();
  const Timed t = time_evaluate(model, st, poses, {}, repeats);
  e.seconds = t.seconds;
  e.result = t.result;
  return e;
}

double largest_force(const magnetics::Result& r) {
  double m = 0;
  for (const Vec3& f : r.force) m = std::max(m, f.norm());
  return m;
}

/// Largest change of any body's force between two results, over the largest force of `ref`.
double largest_change(const magnetics::Result& r, const magnetics::Result& ref) {
  double m = 0;
  for (std::size_t b = 0; b < ref.force.size(); ++b) m = std::max(m, (r.force[b] - ref.force[b]).norm());
  return m / std::max(largest_force(ref), 1e-300);
}

struct ErrorStats {
  double max_rel = 0, rms_rel = 0;  ///< over significant bodies, each relative to its own reference force
  double max_over_largest = 0;      ///< largest error of any body over the largest reference force
  int bodies = 0;
};

/// Relative force error over the bodies whose reference force is at least 1% of the largest.
ErrorStats force_error(const magnetics::Result& r, const magnetics::Result& ref) {
  ErrorStats e;
  const double fmax = largest_force(ref);
  double sum2 = 0;
  for (std::size_t b = 0; b < ref.force.size(); ++b) {
    const double fr = ref.force[b].norm();
    if (fr < 0.01 * fmax || fr == 0) continue;
    const double rel = (r.force[b] - ref.force[b]).norm() / fr;
    e.max_rel = std::max(e.max_rel, rel);
    sum2 += rel * rel;
    ++e.bodies;
  }
  e.rms_rel = e.bodies ? std::sqrt(sum2 / e.bodies) : 0;
  e.max_over_largest = largest_change(r, ref);
  return e;
}

json error_at_instant(const scene::Scene& sc, const io::CacheReader& cache, const Args& a, int frame,
                      std::ofstream& csv) {
  const sim::SimState s = cli::resume_state(cache, frame_index(cache, frame), sc);
  const auto poses = poses_of(s);
  const int all = hardware_threads();

  // Reference: refine resolution and theta until the largest force changes by < 0.5%.
  const std::vector<Knobs> ladder = {
      knob("ref r2 th0.3", "default", 2.0, 0.3, 4.0, 6),    knob("ref r3 th0.25", "default", 3.0, 0.25, 4.0, 6),
      knob("ref r4 th0.2", "default", 4.0, 0.2, 4.0, 6),    knob("ref r6 th0.15", "default", 6.0, 0.15, 4.0, 6),
      knob("ref r8 th0.1", "default", 8.0, 0.1, 4.0, 6),
  };
  json conv = json::array();
  std::optional<Evaluated> prev, ref;
  bool converged = false;
  for (const Knobs& k : ladder) {
    // Estimate the cell count before building (cells grow with resolution cubed).
    if (prev && prev->cells * std::pow(k.resolution / prev->knobs.resolution, 3) > a.max_ref_cells) break;
    const auto t0 = Clock::now();
    Evaluated e = evaluate_knobs(sc, k, poses, all, 1, 1e-10);
    const double change = prev ? largest_change(prev->result, e.result) : NAN;
    conv.push_back({{"label", k.label},
                    {"cells", e.cells},
                    {"seconds", seconds_since(t0)},
                    {"largest_force_N", largest_force(e.result)},
                    {"change_from_previous", prev ? json(change) : json(nullptr)},
                    {"induction_iterations", e.result.induction.iterations},
                    {"induction_residual", e.result.induction.residual},
                    {"induction_converged", e.result.induction.converged}});
    std::cerr << "  " << a.label << " frame " << frame << ": " << k.label << ", " << e.cells << " cells, max |F| "
              << largest_force(e.result) << " N, change " << change << ", induction "
              << e.result.induction.iterations << " it, residual " << e.result.induction.residual << "\n";
    prev = e;
    // A level whose induction solve did not converge is reported but never becomes the reference.
    if (e.result.induction.converged || !ref) ref = e;
    if (!e.result.induction.converged) break;
    if (!std::isnan(change) && change < 0.005) {
      converged = true;
      break;
    }
  }

  // The change between refinements does not bound the reference's own error: with first-order
  // convergence in the cell size h (what the ladder shows near contact), the error of the last
  // level is about its change times h_last / (h_prev - h_last). Report that estimate.
  double estimated_ref_error = NAN;
  if (conv.size() >= 2) {
    const double r_prev = ladder[conv.size() - 2].resolution, r_last = ladder[conv.size() - 1].resolution;
    const double change = conv.back()["change_from_previous"].get<double>();
    estimated_ref_error = change * (1 / r_last) / (1 / r_prev - 1 / r_last);
  }

  // Settings under test.
  const std::vector<Knobs> knobs = {
      knob("draft", "draft"),
      knob("default", "default"),
      knob("high", "high"),
      knob("default r0.5", "default", 0.5),
      knob("default r1.5", "default", 1.5),
      knob("default r2", "default", 2.0),
      knob("default th0.3", "default", 1.0, 0.3),
      knob("default th0.7", "default", 1.0, 0.7),
      knob("default th0.9", "default", 1.0, 0.9),
      knob("default near0", "default", 1.0, std::nullopt, 0.0),
      tolerance_knob("default tol1e-7", 1e-7),
      tolerance_knob("default tol1e-5", 1e-5),
      tolerance_knob("default tol1e-4", 1e-4),
      tolerance_knob("default tol1e-3", 1e-3),
  };
  json rows = json::array();
  std::map<std::string, magnetics::Result> results;  // to show what the tolerance alone changes
  for (const Knobs& k : knobs) {
    Evaluated e;
    try {
      e = evaluate_knobs(sc, k, poses, 1, 3, std::nullopt);
    } catch (const std::exception& ex) {
      std::cerr << "  " << k.label << ": " << ex.what() << "\n";
      continue;
    }
    const ErrorStats err = force_error(e.result, ref->result);
    results[k.label] = e.result;
    const bool default_preset = k.label == "default" || k.induction_tolerance;
    const auto tight = results.find("default tol1e-7");
    const double from_default = default_preset && tight != results.end() ? largest_change(e.result, tight->second) : NAN;
    const scene::Scene kn = with_knobs(sc, k);
    csv << a.label << ',' << frame << ',' << k.label << ',' << kn.magnetics.quality << ','
        << (kn.magnetics.cell_size ? *kn.magnetics.cell_size : 0.0) << ',' << kn.magnetics.cells_per_extent << ','
        << kn.magnetics.theta << ',' << kn.magnetics.near_field << ',' << e.cells << ',' << 1e3 * e.seconds << ','
        << err.max_rel << ',' << err.rms_rel << ',' << err.max_over_largest << ',' << err.bodies << ',' << e.result.induction.iterations << ','
        << e.result.induction.residual << '\n';
    csv.flush();
    rows.push_back({{"label", k.label}, {"cells", e.cells}, {"ms", 1e3 * e.seconds}, {"max_rel_error", err.max_rel},
                    {"rms_rel_error", err.rms_rel}, {"max_error_over_largest_force", err.max_over_largest},
                    {"bodies", err.bodies}, {"induction_iterations", e.result.induction.iterations},
                    {"change_from_tight_solve", std::isnan(from_default) ? json(nullptr) : json(from_default)}});
    std::cerr << "  " << a.label << " frame " << frame << ": " << k.label << ", " << e.cells << " cells, "
              << 1e3 * e.seconds << " ms, force error max " << err.max_rel << " rms " << err.rms_rel << " over "
              << err.bodies << " bodies, " << e.result.induction.iterations << " induction iterations"
              << (std::isnan(from_default) ? "" : ", change from the 1e-7 solve " + std::to_string(from_default)) << "\n";
  }
  // The default row was evaluated before the tight solve it is compared with.
  if (results.count("default") && results.count("default tol1e-7")) {
    for (json& row : rows) {
      if (row["label"] == "default") row["change_from_tight_solve"] = largest_change(results["default"], results["default tol1e-7"]);
    }
  }
  return {{"frame", frame}, {"reference", conv}, {"reference_converged", converged},
          {"reference_error_estimate_first_order", std::isnan(estimated_ref_error) ? json(nullptr) : json(estimated_ref_error)},
          {"reference_label", ref->knobs.label}, {"settings", rows}};
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args a = parse_args(argc, argv);
    std::filesystem::create_directories(a.out);
    const scene::Scene sc = scene::load_scene(a.scene);
    const io::CacheReader cache(a.cache);
    if (cache.scene_hash() != sc.hash) throw std::runtime_error(a.cache + " was not baked from " + a.scene);
    const magnetics::Model model = scene::build_magnetics_model(sc);

    // Results of earlier runs with other --parts are kept.
    const std::filesystem::path json_path = std::filesystem::path(a.out) / (a.label + ".json");
    json out = json::object();
    if (std::filesystem::exists(json_path)) {
      std::ifstream in(json_path);
      out = json::parse(in, nullptr, false);
      if (out.is_discarded()) out = json::object();
    }
    out["label"] = a.label;
    out["scene"] = a.scene;
    out["cells"] = model.cell_count();
    out["bodies"] = sc.bodies.size();
    out["dt_ms"] = 1e3 * sc.dt;
    out["window"] = {{"frame", a.window_frame}, {"frames", a.window_frames}};
    out["hardware_threads"] = hardware_threads();
    if (a.wants("timing")) {
      out["timing"] = json::array();
      for (int t : a.threads) {
        const int n = t > 0 ? t : hardware_threads();
        std::cerr << a.label << ": timing " << a.window_frames << " frames from frame " << a.window_frame << " on " << n
                  << " thread(s)\n";
        out["timing"].push_back(time_window(sc, model, cache, a, n));
        std::cerr << "  " << out["timing"].back().dump() << "\n";
      }
      std::ifstream load("/proc/loadavg");
      std::string l1;
      load >> l1;
      out["load_after_timing"] = l1;
    }
    if (a.wants("gain")) {
      std::cerr << a.label << ": gain\n";
      out["gain"] = measure_gain(sc, model, cache, a);
      std::cerr << "  " << out["gain"].dump() << "\n";
    }
    if (!a.wants("error")) {
      std::ofstream(json_path) << out.dump(2) << "\n";
      return 0;
    }

    std::ofstream csv(std::filesystem::path(a.out) / (a.label + "_time_vs_error.csv"));
    csv << "scene,frame,setting,quality,cell_size_m,cells_per_extent,theta,near_field,cells,ms_per_eval_1thread,"
           "max_rel_force_error,rms_rel_force_error,max_error_over_largest_force,bodies,induction_iterations,"
           "induction_residual\n";
    out["error"] = json::array();
    for (int f : a.instants) {
      std::cerr << a.label << ": run time against error at frame " << f << "\n";
      out["error"].push_back(error_at_instant(sc, cache, a, f, csv));
    }
    std::ofstream(json_path) << out.dump(2) << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "paper_table: " << e.what() << "\n";
    return 1;
  }
}
