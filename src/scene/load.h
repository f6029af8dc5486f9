// Scene files: parse (YAML -> SceneSpec), validate (-> Scene), or both.
#pragma once

#include <string>

#include "diagnostics.h"
#include "scene.h"
#include "spec.h"

namespace magbake::scene {

/// Checks a SceneSpec and builds the Scene (SI units, presets resolved, meshes loaded relative
/// to the scene file's folder, mass properties computed). Problems go to `diag`; the returned
/// Scene is only meaningful when `diag` stays empty.
Scene validate_scene(const SceneSpec& spec, Diagnostics& diag);

/// parse + validate; throws SceneError listing every problem.
Scene load_scene(const std::string& path);
/// The same from text already in memory (`file` names it in messages and anchors mesh paths).
Scene load_scene_text(const std::string& text, const std::string& file);

/// outputs.field and outputs.preview of a scene's text, in SI units, without validating the rest
/// (meshes are not loaded): what `magbake field` and `preview` read from a cache. Returns ""
/// or, when those outputs do not validate (a bad pattern or path stored in a cache), the
/// problems; both outputs are then unset.
std::string outputs_of_text(const std::string& text, std::optional<FieldOutput>& field,
                            std::optional<PreviewOutput>& preview);

/// Hex SHA-256 of a byte string.
std::string sha256_hex(const std::string& bytes);

}  // namespace magbake::scene
