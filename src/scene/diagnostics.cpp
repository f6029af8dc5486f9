#include "diagnostics.h"

#include <algorithm>
#include <numeric>
#include <sstream>

namespace magbake::scene {

std::string Diagnostics::format() const {
  std::ostringstream os;
  for (const Diagnostic& d : items_) {
    os << file_;
    if (d.loc.line > 0) os << ':' << d.loc.line << ':' << d.loc.col;
    os << ": ";
    if (!d.path.empty()) os << d.path << ": ";
    os << d.message << '\n';
  }
  return os.str();
}

namespace {
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), 0);
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}
}  // namespace

std::string did_you_mean(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = 1 + word.size() / 4 + 1;
  for (const std::string& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) best_d = d, best = c;
  }
  return best;
}

}  // namespace magbake::scene
