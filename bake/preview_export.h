// Preview export shared by `magbake preview` and `magbake bake` (outputs.preview).
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "cli.h"

namespace magbake::cli {

/// What to render; unset values come from the cache's outputs.preview, then from defaults.
struct PreviewRequest {
  std::optional<std::pair<int, int>> frames;
  std::string pattern;              ///< "" = outputs.preview.path or <cache>.preview.####.png
  int width = 0, height = 0;        ///< 0 = outputs.preview.size or 960x540
  std::optional<bool> field_lines;  ///< unset = outputs.preview.field_lines
  bool auto_camera = false;         ///< ignore the scene's camera and frame the shot
  std::string contact_sheet;        ///< also write every rendered frame tiled into this PNG
  std::optional<int> every;         ///< every n-th frame, counted from the shot's first frame (default 1)
  bool allow_absolute = false;      ///< an absolute outputs.preview.path may be used
};

/// Renders a cache's frames to PNG. Exit code (0 ok, 1 failure, 2 bad input, 75 interrupted).
int export_preview(const std::string& cache_path, const PreviewRequest& request, const Global& g);

}  // namespace magbake::cli
