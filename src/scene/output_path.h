// Where a scene may write: its outputs stay inside the output folder (docs/scene-format.md,
// "Output paths"). A scene file comes from anyone on a farm; its paths must not reach outside
// the folder the bake was given.
#pragma once

#include <optional>
#include <string>

namespace magbake::scene {

/// Why the scene's `name` cannot name an output file, or nullopt: it must be a plain file name
/// (no '/', '\', NUL or control characters, not "." or "..", at most 200 bytes).
std::optional<std::string> scene_name_error(const std::string& name);

/// Why an output path read from a scene (outputs.cache, outputs.field.path,
/// outputs.preview.path) may not be used, or nullopt. Relative paths must not contain a ".."
/// component (they are resolved inside the output folder). Absolute paths are refused unless
/// `allow_absolute` (the user passed --allow-absolute-outputs).
std::optional<std::string> output_path_error(const std::string& path, bool allow_absolute);

}  // namespace magbake::scene
