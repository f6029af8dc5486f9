// Messages about a scene file, each tied to a place in it (file:line:col, 1-based).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace magbake::scene {

/// A position in the scene file, 1-based; line 0 means "unknown".
struct Loc {
  int line = 0;
  int col = 0;
};

/// One problem found in a scene: where, which key (e.g. bodies[2].shape.box), and what.
struct Diagnostic {
  Loc loc;
  std::string path;
  std::string message;
};

/// The problems found in one scene file, in the order they were found.
class Diagnostics {
 public:
  explicit Diagnostics(std::string file = "") : file_(std::move(file)) {}
  void add(Loc loc, std::string path, std::string message) {
    items_.push_back({loc, std::move(path), std::move(message)});
  }
  bool empty() const { return items_.empty(); }
  const std::vector<Diagnostic>& items() const { return items_; }
  const std::string& file() const { return file_; }
  /// One line per problem: "file:line:col: path: message".
  std::string format() const;

 private:
  std::string file_;
  std::vector<Diagnostic> items_;
};

/// Thrown when a scene cannot be loaded; carries every problem found.
class SceneError : public std::runtime_error {
 public:
  explicit SceneError(Diagnostics d) : std::runtime_error(d.format()), diagnostics_(std::move(d)) {}
  const Diagnostics& diagnostics() const { return diagnostics_; }

 private:
  Diagnostics diagnostics_;
};

/// The closest of `candidates` to `word` if it is close enough to be a likely misspelling
/// (edit distance at most 1 + length/4), else "".
std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace magbake::scene
