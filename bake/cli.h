// Shared pieces of the magbake commands: exit codes, scene loading with diagnostics, output.
#pragma once

#include <nlohmann/json.hpp>

#include <functional>
#include <optional>
#include <string>

#include "io/diff.h"
#include "scene/load.h"
#include "sim/sim_state.h"

namespace magbake::cli {

/// Process exit codes (DESIGN.md).
enum Exit : int { kOk = 0, kFailure = 1, kUsage = 2, kInterrupted = 75 };

/// Options every command shares.
struct Global {
  int threads = 0;  ///< 0 = all cores
  bool quiet = false;
  bool verbose = false;
};

/// Loads a scene, or prints every problem (file:line:col) to stderr and returns nullopt.
std::optional<scene::Scene> load_or_report(const std::string& path);

/// A 3-vector as a JSON array.
nlohmann::json json_vec(const Eigen::Vector3d& v);

/// Writes JSON to stdout (pretty, one trailing newline).
void print_json(const nlohmann::json& j);

/// Scenes with more bodies than this get a shortened body list in summaries (one screen).
inline constexpr std::size_t kSummaryBodies = 24;

/// A human-readable one-screen summary of a scene (used by check and info); `all_bodies` lists
/// every body even in a large scene.
std::string scene_summary(const scene::Scene& s, bool all_bodies = false);

/// The same summary as JSON (`check --json`): scene, name, sha256, units, time {fps, frames,
/// frame_count, duration_seconds, dt_seconds, substeps}, gravity (m/s²), magnetics {quality,
/// cell_size_m or cells_across and soft_cells_across, theta, near_field_cells, near_field_order,
/// induction, induction_tolerance, external_field_T (at t = 0), external_field_animated}, materials [{name, kind, remanence_T, chi,
/// density, friction, restitution, damping, color}] (keys present where set), bodies [{name,
/// shape, material, parts, motion, mass_kg, friction, restitution, damping {linear, angular},
/// color}] (every body), joints [{name, type, bodies [a, b or "world"], limits (rad or m)}],
/// outputs {cache, usd, field, preview}. SI throughout.
nlohmann::json scene_summary_json(const scene::Scene& s);

/// `check`: validates, prints the summary and the expected cost of a bake (from a trial bake of
/// `trial_seconds` of wall time at most; 0 = evaluation cost only); `json` for the stable form.
int cmd_check(const std::string& path, double trial_seconds, bool json, const Global& g);
/// "A-B" or "A" -> a, b.
bool parse_range(const std::string& text, int& a, int& b);
/// Test seams of `bake` (unset in the program): a state hook run after every magnetics
/// evaluation, and a callback run before each frame is written (it may throw io::h5::Error to
/// act as a full disk).
struct BakeHooks {
  std::function<void(int frame, sim::SimState& state)> after_magnetics;
  std::function<void(int frame)> before_write;
};

/// `bake`: `allow_absolute` lets absolute output paths of the scene be used (scene/output_path.h).
/// `cache_only` skips the field volumes and previews that the scene's outputs ask for. A
/// complete cache of the same name is replaced only with `force` (else exit 2, nothing touched).
int cmd_bake(const std::string& path, const std::string& out_dir, const std::string& frames, bool resume,
             const Global& g, bool strict = false, bool allow_absolute = false, const BakeHooks& hooks = {},
             bool cache_only = false, bool force = false);
int cmd_info_cache(const std::string& path, bool all_bodies = false);

/// `export --usd` (docs/usd.md): the cache as a USD stage.
struct UsdRequest {
  std::string usd;                            ///< output file (.usda)
  std::optional<std::pair<int, int>> frames;  ///< inclusive; unset = every frame of the cache
  /// Field volume files to reference ("name.####.vdb"); "" = outputs.field.path's file name beside
  /// the cache when those files exist; "none" = no volume.
  std::string field_pattern;
  bool field_lines = false;  ///< the previews' field lines as BasisCurves, traced at every frame
};
int cmd_export_usd(const std::string& cache, const UsdRequest& request, const Global& g);
int cmd_info(const std::string& path, const Global& g);
int cmd_eval(const std::string& path, double time, bool json, const Global& g);
int cmd_diff(const std::string& a, const std::string& b, const io::DiffOptions& options, const Global& g);
int cmd_probe(const std::string& path, const std::vector<std::string>& at, const std::string& points_file, double time,
              bool json, const Global& g);

}  // namespace magbake::cli
