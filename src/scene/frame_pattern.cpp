#include "frame_pattern.h"

#include <cassert>

namespace magbake::scene {
namespace {

// The one frame field of a pattern: [begin, end) in the text and its zero-padded width
// (0 = as many digits as needed).
struct Field {
  std::size_t begin = std::string::npos, end = std::string::npos;
  int width = 0;
};

// Scans `p`; fills `f` with its frame field (if any) and returns an error text, or "" when valid.
std::string scan(const std::string& p, Field& f) {
  if (p.empty()) return "empty file pattern";
  if (p.find('\0') != std::string::npos) return "file pattern contains a NUL character";
  int fields = 0;
  for (std::size_t i = 0; i < p.size();) {
    if (p[i] == '#') {
      std::size_t j = i;
      while (j < p.size() && p[j] == '#') ++j;
      const std::size_t n = j - i;
      if (n > static_cast<std::size_t>(kMaxFrameDigits)) {
        return "a run of " + std::to_string(n) + " '#' in the file pattern; at most " + std::to_string(kMaxFrameDigits);
      }
      f = Field{i, j, static_cast<int>(n)};
      ++fields;
      i = j;
    } else if (p[i] == '%') {
      if (i + 1 < p.size() && p[i + 1] == '%') {
        i += 2;
        continue;
      }
      std::size_t j = i + 1;
      int width = 0;
      if (j < p.size() && p[j] == '0') {
        ++j;
        const std::size_t digits = j;
        while (j < p.size() && p[j] >= '0' && p[j] <= '9' && j - digits < 3) width = 10 * width + (p[j++] - '0');
        if (j == digits || width < 1 || width > kMaxFrameDigits) {
          return "'%0' in the file pattern needs a width from 1 to " + std::to_string(kMaxFrameDigits) + " (e.g. %04d)";
        }
      }
      if (j >= p.size() || p[j] != 'd') {
        std::string msg = "'";
        msg.append(p, i, std::min<std::size_t>(j - i + 1, 8));
        msg.append("' in the file pattern: only #### or %d / %0Nd (e.g. %04d) name the frame; write %% for a literal %");
        return msg;
      }
      f = Field{i, j + 1, width};
      ++fields;
      i = j + 1;
    } else {
      ++i;
    }
  }
  if (fields > 1) return "the file pattern names the frame " + std::to_string(fields) + " times; use one #### or %04d";
  // Without a frame field every frame would need a name made up for it (field.vdb -> field.7.vdb
  // until 2026-12-06): a renderer's sequence loader finds no sequence there.
  if (fields == 0) return "the file pattern names no frame: put #### (or %04d) where the frame number goes, e.g. field.####.vdb";
  return "";
}

// '%%' -> '%' in a piece of pattern text.
std::string literal(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    out += s[i];
    if (s[i] == '%' && i + 1 < s.size() && s[i + 1] == '%') ++i;
  }
  return out;
}

// printf("%0*d") without printf: the sign counts towards the width ("-01" for -1 in 3).
std::string padded(int frame, int width) {
  const long long magnitude = frame < 0 ? -static_cast<long long>(frame) : static_cast<long long>(frame);
  const std::string digits = std::to_string(magnitude);
  std::string out;
  if (frame < 0) out.push_back('-');
  for (int k = static_cast<int>(out.size() + digits.size()); k < width; ++k) out.push_back('0');
  out.append(digits);
  return out;
}

}  // namespace

std::optional<std::string> frame_pattern_error(const std::string& pattern) {
  Field f;
  std::string e = scan(pattern, f);
  if (e.empty()) return std::nullopt;
  return e;
}

std::string expand_frame_pattern(const std::string& pattern, int frame) {
  Field f;
  [[maybe_unused]] const std::string e = scan(pattern, f);
  assert(e.empty());
  assert(f.begin != std::string::npos);
  return literal(pattern.substr(0, f.begin)) + padded(frame, f.width) + literal(pattern.substr(f.end));
}

}  // namespace magbake::scene
