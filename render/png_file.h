// PNG files through libpng.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace magbake::render {

/// Writes an RGBA8 image (top row first) as an RGB PNG, atomically (temporary name, renamed).
/// Throws std::runtime_error.
void write_png(const std::string& path, const std::vector<std::uint8_t>& rgba, int width, int height);

/// Reads a PNG into RGBA8 (top row first). Throws std::runtime_error.
std::vector<std::uint8_t> read_png(const std::string& path, int& width, int& height);

}  // namespace magbake::render
