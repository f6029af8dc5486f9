// Wedges: one shot baked at every combination of a few scene settings (docs/farm.md).
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace magbake::cli {

/// One varied setting: a dotted key path into the scene file (`magnetics.theta`,
/// `materials.steel.chi`, `bodies.ball.position`: a list element is named by its `name` or its
/// index) and the values it takes (YAML scalars or flow sequences, e.g. `[0, 0, 5]`).
struct Wedge {
  std::string key;
  std::vector<std::string> values;
};

/// "KEY=V1,V2,..." (commas inside [] belong to a value). False, with `error`, when malformed.
bool parse_wedge(const std::string& text, Wedge& w, std::string& error);

/// Every combination, the first wedge varying slowest: each a list of (key, value).
std::vector<std::vector<std::pair<std::string, std::string>>> wedge_combinations(const std::vector<Wedge>& wedges);

/// The scene file's text with each key set to its value, and relative mesh files made absolute
/// against `scene_dir` (the folder of the original scene), so the result can live anywhere.
/// Throws std::runtime_error naming the key when a path does not lead through the scene.
std::string wedge_scene_text(const std::string& scene_text, const std::vector<std::pair<std::string, std::string>>& set,
                             const std::string& scene_dir);

/// A folder name for a combination: index and settings, characters outside [A-Za-z0-9._=-]
/// replaced by '_' (e.g. "003_magnetics.theta=0.3_materials.steel.chi=700").
std::string wedge_folder_name(int index, const std::vector<std::pair<std::string, std::string>>& set);

}  // namespace magbake::cli
