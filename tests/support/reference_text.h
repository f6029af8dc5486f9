// Helpers of the tests that read the reference sets under tests/data (scripts/make_*_reference.py).
#pragma once

#include <string>

namespace magbake::testing {

/// `s` with every `what` replaced by `with` (a reference case's scene template filled in).
inline std::string replace_all(std::string s, const std::string& what, const std::string& with) {
  for (std::size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + with.size())) {
    s.replace(at, what.size(), with);
  }
  return s;
}

#ifdef MAGBAKE_SOURCE_DIR
/// The source tree (the test target's MAGBAKE_SOURCE_DIR), where tests/data lives.
inline std::string source_dir() { return MAGBAKE_SOURCE_DIR; }
#endif

}  // namespace magbake::testing
