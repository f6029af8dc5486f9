// magbake: command-line baker for magnetic rigid-body shots.
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>

#include "cli.h"
#include "farm.h"
#include "field_export.h"
#include "preview_export.h"
#include "progress.h"
#include "io/h5.h"
#include "geometry/shapes.h"
#include "magnetics/system.h"

namespace {

using namespace magbake;

// Library demo: the paper's cube pair (Fig. 6).
int run_cubes(double gap_mm, double cell_mm, double theta) {
  geometry::BoxShape cube(magnetics::Vec3(0.01, 0.01, 0.01));
  magnetics::Material j1;
  j1.kind = magnetics::MaterialKind::kPermanent;
  j1.remanence = 1.0;
  std::vector<magnetics::BodySpec> bodies(2);
  for (auto& b : bodies) b.parts.push_back({&cube, {}, j1});
  magnetics::BuildSettings bs;
  bs.cell_size = cell_mm * 1e-3;
  const magnetics::Model model = magnetics::build_model(bodies, bs);
  magnetics::State state;
  state.resize(model);
  state.body_pose[1].position = magnetics::Vec3(0, 0, 0.01 + gap_mm * 1e-3);
  magnetics::Settings st;
  st.theta = theta;
  magnetics::Result r;
  magnetics::evaluate(model, st, state, r);
  std::printf("two 1 cm cubes, J = 1 T, gap %.3g mm, %d cells, theta %.2f\n", gap_mm, model.cell_count(), theta);
  std::printf("force on upper cube: %.5f %.5f %.5f N\n", r.force[1][0], r.force[1][1], r.force[1][2]);
  std::printf("pairs: %lld node, %lld cell, %lld near-field\n", (long long)r.stats.node_pairs,
              (long long)r.stats.cell_pairs, (long long)r.stats.near_pairs);
  return 0;
}

}  // namespace

// Numbers from the command line: finite and within [lo, hi], else false after logging why.
bool number_ok(const char* option, double v, double lo, double hi) {
  if (std::isfinite(v) && v >= lo && v <= hi) return true;
  spdlog::error("{} must be a number from {:g} to {:g}, got {}", option, lo, hi, v);
  return false;
}

// Runs a command that reads a cache: what it lets escape is a cache it could not use (its own
// write failures are caught where they happen), so it is bad input, exit 2.
template <class Command>
int cache_reader_command(const std::string& cache, Command command) {
  try {
    return command();
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    spdlog::error("{}: {}", cache, e.what());
    return cli::kUsage;
  }
}

int run(int argc, char** argv) {
  CLI::App app{"magbake - baker for magnetic rigid-body shots (scene -> HDF5 cache, field volumes, previews)"};
  app.require_subcommand(1);
  app.fallthrough();  // global options (--threads, -q, -v) also work after the subcommand
  cli::Global g;
  app.add_option("--threads", g.threads, "worker threads (0 = all cores)")->capture_default_str();
  app.add_flag("-q,--quiet", g.quiet, "only warnings and errors on stderr");
  app.add_flag("-v,--verbose", g.verbose, "debug messages on stderr");

  std::string scene_path;
  double time = 0;
  bool json = false;

  std::string out_dir, frames;
  bool resume = false;
  auto* bake = app.add_subcommand("bake", "simulate a scene into an HDF5 cache (exit 0 ok, 1 failure, 2 bad input, 75 interrupted)");
  bake->add_option("scene", scene_path, "scene file (YAML)")->required();
  bake->add_option("-o,--output", out_dir, "output folder (the cache keeps its file name from outputs.cache)");
  bake->add_option("--frames", frames, "frame range A-B to write (simulation starts at the scene's first frame)");
  bake->add_flag("--resume", resume, "continue an interrupted bake from its last complete frame");
  bool strict = false;
  bake->add_flag("--strict", strict, "exit 1 when the bake ends with warnings (overlaps, energy growth, bodies lost)");
  bool allow_absolute = false;
  bake->add_flag("--allow-absolute-outputs", allow_absolute,
                 "let the scene's absolute output paths be used (by default a scene writes inside the output folder)");

  bool force = false;
  bake->add_flag("--force", force, "replace a complete cache of the same name (without it, bake refuses to)");
  bool cache_only = false;
  bake->add_flag("--cache-only", cache_only,
                 "write the cache only, not the field volumes and previews of outputs (farm: export jobs do those)");

  cli::FarmRequest farm_req;
  auto* farm = app.add_subcommand("farm", "submit a shot to a farm: a simulation job, then export array jobs (docs/farm.md)");
  farm->add_option("scene", farm_req.scene, "scene file (YAML)")->required();
  farm->add_option("--engine", farm_req.engine, "scheduler (slurm)")->capture_default_str();
  farm->add_option("--chunk", farm_req.chunk, "frames per export array task")->capture_default_str();
  farm->add_option("--partition", farm_req.partition, "Slurm partition (default: the cluster's)");
  farm->add_option("--time", farm_req.time_limit, "Slurm time limit of each job, e.g. 04:00:00");
  farm->add_option("--cpus", farm_req.cpus, "CPUs of each job (magbake --threads there)")->capture_default_str();
  farm->add_option("-o,--output", farm_req.out_dir, "shot folder (default: the folder of outputs.cache)");
  farm->add_option("--magbake", farm_req.magbake, "magbake program the jobs run (default: this one)");
  farm->add_option("--wedge", farm_req.wedges,
                   "KEY=V1,V2: bake every combination of the wedged scene settings (repeatable; docs/farm.md)");
  farm->add_flag("--force", farm_req.force,
                 "submit even if the shot's cache (or a wedge case's) is complete: the jobs bake it again");
  farm->add_flag("--allow-absolute-outputs", farm_req.allow_absolute,
                 "without -o, let an absolute outputs.cache of the scene name the shot folder");
  std::string wedge_file;
  farm->add_option("--wedge-file", wedge_file, "file of KEY=V1,V2 lines (# comments), as more --wedge options");
  auto* submit_flag = farm->add_flag("--submit", farm_req.submit, "write the scripts under <shot>/farm/ and submit them");
  bool dry_run = false;
  farm->add_flag("--dry-run", dry_run, "print the scripts, write and submit nothing (the default)")->excludes(submit_flag);

  std::string cache_a, cache_b;
  io::DiffOptions diff_options;
  auto* diff = app.add_subcommand("diff", "compare two caches (exit 0 same, 1 differ, 2 error)");
  diff->add_option("a", cache_a, "first cache (.h5)")->required();
  diff->add_option("b", cache_b, "second cache (.h5)")->required();
  diff->add_option("--atol", diff_options.atol, "absolute tolerance (SI units)")->capture_default_str();
  diff->add_option("--rtol", diff_options.rtol, "relative tolerance")->capture_default_str();
  diff->add_option("--angle-tol", diff_options.angle_tol, "orientation tolerance, radians")->capture_default_str();
  diff->add_flag("--exact", diff_options.exact, "require bit equality (wall times are never compared)");

  std::string field_cache, field_frames, field_bounds;
  cli::FieldRequest field_req;
  double field_voxel = 0;
  std::string field_margin, field_threshold;
  auto* field = app.add_subcommand("field", "B-field volumes (OpenVDB, one per frame) from a cache");
  field->add_option("cache", field_cache, "cache (.h5)")->required();
  field->add_option("--frames", field_frames, "frame range A-B (default: every frame of the cache)");
  field->add_option("-o,--output", field_req.pattern, "file pattern, e.g. out/field.####.vdb (default: outputs.field.path)");
  field->add_option("--voxel", field_voxel, "voxel edge in metres (default: outputs.field.voxel, else region/128)");
  field->add_option("--bounds", field_bounds, "region xmin,ymin,zmin,xmax,ymax,zmax in metres (default: auto)");
  field->add_option("--margin", field_margin,
                    "margin around the magnetic bodies for auto bounds, metres, or auto (default: outputs.field.margin, else auto)");
  field->add_option("--every", field_req.every,
                    "every n-th frame, counted from the shot's first frame (default: outputs.field.every, else 1)")
      ->check(CLI::Range(1, 1000000));
  field->add_option("--threshold", field_threshold,
                    "voxels where the bodies' |B| is below this (tesla) stay inactive, or auto: 0.3% of the strongest "
                    "remanence or applied field (default: outputs.field.threshold, else auto)");
  field->add_option("--theta", field_req.theta, "tree opening angle (accuracy, see docs)")->capture_default_str();
  field->add_flag("--allow-absolute-outputs", field_req.allow_absolute, "let an absolute outputs.field.path stored in the cache be used");

  std::string preview_cache, preview_frames, preview_size;
  cli::PreviewRequest preview_req;
  bool lines_on = false, lines_off = false;
  auto* preview = app.add_subcommand("preview", "PNG preview frames of a cache (offscreen OpenGL)");
  preview->add_option("cache", preview_cache, "cache (.h5)")->required();
  preview->add_option("--frames", preview_frames, "frame range A-B (default: every frame)");
  preview->add_option("-o,--output", preview_req.pattern, "file pattern, e.g. out/preview.####.png");
  preview->add_option("--every", preview_req.every, "every n-th frame, counted from the shot's first frame (default 1)")
      ->check(CLI::Range(1, 1000000));
  preview->add_option("--size", preview_size, "image size WxH (default: outputs.preview.size or 960x540)");
  preview->add_flag("--field-lines", lines_on, "draw field lines (streamlines of B)");
  preview->add_flag("--no-field-lines", lines_off, "no field lines");
  preview->add_flag("--auto-camera", preview_req.auto_camera, "frame the shot automatically, ignoring the scene's camera");
  preview->add_option("--contact-sheet", preview_req.contact_sheet, "also write all frames tiled into this PNG");
  preview->add_flag("--allow-absolute-outputs", preview_req.allow_absolute,
                    "let an absolute outputs.preview.path stored in the cache be used");

  std::string export_cache, export_frames;
  cli::UsdRequest usd_req;
  auto* exp = app.add_subcommand("export", "a cache as a USD stage for DCCs and renderers (docs/usd.md)");
  exp->add_option("cache", export_cache, "cache (.h5)")->required();
  exp->add_option("--usd", usd_req.usd, "USD file to write (.usda)")->required();
  exp->add_option("--frames", export_frames, "frame range A-B (default: every frame of the cache)");
  exp->add_option("--field", usd_req.field_pattern,
                  "field volumes to reference, e.g. out/field.####.vdb (default: outputs.field.path beside the cache if "
                  "written; none: no volume)");
  exp->add_flag("--field-lines", usd_req.field_lines,
                "add the previews' field lines as a BasisCurves prim with a time sample per frame");

  auto* check = app.add_subcommand("check", "validate a scene and print a one-screen summary with its cost (exit 0/2)");
  check->add_option("scene", scene_path, "scene file (YAML)")->required();
  double trial_seconds = 2.0;
  check->add_option("--trial", trial_seconds,
                    "seconds of trial bake behind the cost estimate (0 = none; up to 4x longer while its cost per step is still changing)")->capture_default_str()->check(CLI::Range(0.0, 1e6));
  check->add_flag("--json", json, "JSON on stdout (SI units)");

  auto* info = app.add_subcommand("info", "human-readable summary of a scene or a cache");
  info->add_option("file", scene_path, "scene file (YAML) or cache (.h5)")->required();

  auto* eval = app.add_subcommand("eval", "forces, torques and moments of every body at one instant");
  eval->add_option("scene", scene_path, "scene file (YAML)")->required();
  eval->add_option("--time", time, "time in seconds (kinematic bodies at their keyed pose)")->capture_default_str();
  eval->add_flag("--json", json, "JSON on stdout (SI units)");

  std::vector<std::string> at;
  std::string points_file;
  auto* probe = app.add_subcommand("probe", "magnetic flux density B (tesla) at points");
  probe->add_option("scene", scene_path, "scene file (YAML)")->required();
  probe->add_option("--at", at, "a point X,Y,Z in metres (repeatable)")->take_all();
  probe->add_option("--points", points_file, "file with one point per line: x y z or x,y,z (metres)");
  probe->add_option("--time", time, "time in seconds")->capture_default_str();
  probe->add_flag("--json", json, "JSON on stdout");

  double gap = 5, cell = 2.5, theta = 0.5;
  auto* cubes = app.add_subcommand("cubes", "library demo: force between the paper's two 1 cm cube magnets");
  cubes->add_option("--gap", gap, "face gap, mm")->capture_default_str();
  cubes->add_option("--cell", cell, "cell size, mm")->capture_default_str();
  cubes->add_option("--theta", theta, "opening angle")->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : cli::kUsage;
  }

  auto logger = spdlog::stderr_logger_mt("magbake");
  logger->set_pattern("magbake: %l: %v");
  logger->set_level(g.quiet ? spdlog::level::warn : g.verbose ? spdlog::level::debug : spdlog::level::info);
  spdlog::set_default_logger(logger);
  std::unique_ptr<tbb::global_control> threads;
  if (g.threads > 0) {
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, g.threads);
  }

  // Every number given on the command line, before any work (DESIGN.md exit 2).
  if (g.threads < 0 || g.threads > 4096) {
    spdlog::error("--threads must be from 0 (all cores) to 4096, got {}", g.threads);
    return cli::kUsage;
  }
  if (*diff && !(number_ok("--atol", diff_options.atol, 0, 1e30) && number_ok("--rtol", diff_options.rtol, 0, 1e30) &&
                 number_ok("--angle-tol", diff_options.angle_tol, 0, 10))) {
    return cli::kUsage;
  }
  if ((*eval || *probe) && !number_ok("--time", time, -1e9, 1e9)) return cli::kUsage;
  if (*check && !number_ok("--trial", trial_seconds, 0, 1e6)) return cli::kUsage;  // CLI::Range lets NaN through
  if (*field) {
    if (field->count("--voxel") && !number_ok("--voxel", field_voxel, 1e-7, 1e4)) return cli::kUsage;
    // A number in [lo, hi] or the word auto: false (after logging) otherwise.
    auto number_or_auto = [&](const char* option, const std::string& text, double lo, double hi,
                              std::optional<double>& value, bool& is_auto) {
      if (!field->count(option)) return true;
      if (text == "auto") return is_auto = true;
      char* end = nullptr;
      const double v = std::strtod(text.c_str(), &end);
      if (text.empty() || end != text.c_str() + text.size()) {
        spdlog::error("{} expects a number or auto, got '{}'", option, text);
        return false;
      }
      if (!number_ok(option, v, lo, hi)) return false;
      value = v;
      return true;
    };
    if (!number_or_auto("--margin", field_margin, 0, 1e4, field_req.margin, field_req.margin_auto) ||
        !number_or_auto("--threshold", field_threshold, 0, 100, field_req.threshold, field_req.threshold_auto) ||
        !number_ok("--theta", field_req.theta, 0, 1)) {
      return cli::kUsage;
    }
  }
  if (*cubes && !(number_ok("--gap", gap, 0, 1e4) && number_ok("--cell", cell, 0.01, 1e4) && number_ok("--theta", theta, 0, 1))) {
    return cli::kUsage;
  }

  // --frames A-B of the cache readers: unset when empty; false (after logging) when malformed.
  auto frames_option = [](const std::string& text, std::optional<std::pair<int, int>>& out) {
    if (text.empty()) return true;
    int fa = 0, fb = 0;
    if (!cli::parse_range(text, fa, fb)) {
      spdlog::error("--frames expects A-B, got '{}'", text);
      return false;
    }
    out = std::make_pair(fa, fb);
    return true;
  };
  if (*exp) {
    if (!frames_option(export_frames, usd_req.frames)) return cli::kUsage;
    return cli::cmd_export_usd(export_cache, usd_req, g);
  }
  if (*field) {
    if (!frames_option(field_frames, field_req.frames)) return cli::kUsage;
    if (field_voxel > 0) field_req.voxel = field_voxel;
    if (!field_bounds.empty()) {
      double v[6];
      int used = 0;
      const bool parsed = std::sscanf(field_bounds.c_str(), "%lf,%lf,%lf,%lf,%lf,%lf%n", v, v + 1, v + 2, v + 3, v + 4,
                                      v + 5, &used) == 6 &&
                          used == static_cast<int>(field_bounds.size());
      bool finite = parsed;
      for (int k = 0; parsed && k < 6; ++k) finite = finite && std::isfinite(v[k]) && std::abs(v[k]) <= 1e6;
      if (!finite || !(v[0] < v[3] && v[1] < v[4] && v[2] < v[5])) {
        spdlog::error("--bounds expects xmin,ymin,zmin,xmax,ymax,zmax in metres (finite, within 1e6, min < max), got '{}'",
                      field_bounds);
        return cli::kUsage;
      }
      field_req.bounds = magnetics::Box3(magnetics::Vec3(v[0], v[1], v[2]), magnetics::Vec3(v[3], v[4], v[5]));
    }
    cli::install_interrupt_handlers();
    return cache_reader_command(field_cache, [&] { return cli::export_field(field_cache, field_req, g); });
  }
  if (*preview) {
    if (!frames_option(preview_frames, preview_req.frames)) return cli::kUsage;
    int used = 0;
    if (!preview_size.empty() &&
        (std::sscanf(preview_size.c_str(), "%dx%d%n", &preview_req.width, &preview_req.height, &used) != 2 ||
         used != static_cast<int>(preview_size.size()))) {
      spdlog::error("--size expects WxH, got '{}'", preview_size);
      return cli::kUsage;
    }
    if (!preview_size.empty() && !(preview_req.width >= 16 && preview_req.width <= 8192 && preview_req.height >= 16 &&
                                   preview_req.height <= 8192)) {
      spdlog::error("--size must be between 16x16 and 8192x8192, got '{}'", preview_size);
      return cli::kUsage;
    }
    if (lines_on) preview_req.field_lines = true;
    if (lines_off) preview_req.field_lines = false;
    cli::install_interrupt_handlers();
    return cache_reader_command(preview_cache, [&] { return cli::export_preview(preview_cache, preview_req, g); });
  }
  if (*bake) return cli::cmd_bake(scene_path, out_dir, frames, resume, g, strict, allow_absolute, {}, cache_only, force);
  if (*farm) {
    if (farm_req.chunk < 1 || farm_req.chunk > 1000000) {
      spdlog::error("--chunk must be from 1 to 1000000, got {}", farm_req.chunk);
      return cli::kUsage;
    }
    if (farm_req.cpus < 1 || farm_req.cpus > 4096) {
      spdlog::error("--cpus must be from 1 to 4096, got {}", farm_req.cpus);
      return cli::kUsage;
    }
    // Values that go into #SBATCH lines: no spaces, quotes or newlines.
    for (const auto& [option, value] : {std::pair{"--partition", farm_req.partition}, std::pair{"--time", farm_req.time_limit}}) {
      if (value.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.,:-") != std::string::npos) {
        spdlog::error("{} may hold letters, digits and _ . , : - only, got '{}'", option, value);
        return cli::kUsage;
      }
    }
    if (!wedge_file.empty()) {
      std::ifstream in(wedge_file);
      if (!in) {
        spdlog::error("--wedge-file {}: cannot read it", wedge_file);
        return cli::kUsage;
      }
      std::string line;
      while (std::getline(in, line)) {
        const auto a = line.find_first_not_of(" \t\r"), b = line.find_last_not_of(" \t\r");
        if (a == std::string::npos || line[a] == '#') continue;
        farm_req.wedges.push_back(line.substr(a, b - a + 1));
      }
    }
    return cli::cmd_farm(farm_req, g);
  }
  if (*diff) return cli::cmd_diff(cache_a, cache_b, diff_options, g);
  if (*check) return cli::cmd_check(scene_path, trial_seconds, json, g);
  if (*info) return cli::cmd_info(scene_path, g);
  if (*eval) return cli::cmd_eval(scene_path, time, json, g);
  if (*probe) return cli::cmd_probe(scene_path, at, points_file, time, json, g);
  if (*cubes) return run_cubes(gap, cell, theta);
  return cli::kUsage;
}

int main(int argc, char** argv) {
  io::h5::no_atexit();
  // No exception leaves main: whatever a command did not catch is reported in one line.
  try {
    return run(argc, argv);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "magbake: error: out of memory\n");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "magbake: error: %s\n", e.what());
  } catch (...) {
    std::fprintf(stderr, "magbake: error: unknown failure\n");
  }
  return cli::kFailure;
}
