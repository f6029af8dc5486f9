// Per-frame output file names ("out/field.####.vdb"): parsed and expanded by our own code, never
// handed to printf, so a pattern from a scene, a cache or the command line cannot read memory.
#pragma once

#include <optional>
#include <string>

namespace magbake::scene {

/// Widest frame-number field a pattern may ask for (#### or %0Nd).
inline constexpr int kMaxFrameDigits = 12;

/// Why `pattern` is not a valid per-frame file pattern, or nullopt when it is. Valid: exactly one
/// run of 1-12 '#' (the frame zero-padded to that width) or one printf-style %d / %0Nd (N <= 12);
/// "%%" is a literal '%'. Anything else with '%' (%s, %n, %x, a width without 0, ...), no or two
/// frame fields, an empty pattern or a NUL is rejected.
std::optional<std::string> frame_pattern_error(const std::string& pattern);

/// The file name of `frame` (may be negative: "-001"). Precondition: frame_pattern_error is nullopt.
std::string expand_frame_pattern(const std::string& pattern, int frame);

}  // namespace magbake::scene
