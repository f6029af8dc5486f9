#include "wedge.h"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <stdexcept>

#include <spdlog/fmt/fmt.h>

namespace magbake::cli {

bool parse_wedge(const std::string& text, Wedge& w, std::string& error) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size()) {
    error = "--wedge expects KEY=V1,V2,... (e.g. magnetics.theta=0.3,0.5), got '" + text + "'";
    return false;
  }
  w.key = text.substr(0, eq);
  if (w.key.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-") != std::string::npos ||
      w.key.front() == '.' || w.key.back() == '.' || w.key.find("..") != std::string::npos) {
    error = "--wedge key '" + w.key + "' must be a dotted path of names (letters, digits, _ and -)";
    return false;
  }
  w.values.clear();
  std::string cur;
  int depth = 0;
  for (char c : text.substr(eq + 1)) {
    if (c == '[') ++depth;
    if (c == ']') --depth;
    if (c == ',' && depth == 0) {
      w.values.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  w.values.push_back(cur);
  for (const std::string& v : w.values) {
    if (v.empty() || depth != 0) {
      error = "--wedge " + w.key + ": an empty or unbalanced value in '" + text + "'";
      return false;
    }
  }
  return true;
}

std::vector<std::vector<std::pair<std::string, std::string>>> wedge_combinations(const std::vector<Wedge>& wedges) {
  std::vector<std::vector<std::pair<std::string, std::string>>> out{{}};
  for (const Wedge& w : wedges) {
    std::vector<std::vector<std::pair<std::string, std::string>>> next;
    for (const auto& prefix : out) {
      for (const std::string& v : w.values) {
        next.push_back(prefix);
        next.back().emplace_back(w.key, v);
      }
    }
    out = std::move(next);
  }
  return out;
}

namespace {

// Relative `file:` of every mesh shape made absolute against `dir`.
void absolutize_meshes(YAML::Node node, const std::filesystem::path& dir) {
  if (node.IsMap()) {
    if (node["mesh"] && node["mesh"].IsMap() && node["mesh"]["file"] && node["mesh"]["file"].IsScalar()) {
      const std::filesystem::path f = node["mesh"]["file"].as<std::string>();
      if (f.is_relative()) node["mesh"]["file"] = (dir / f).lexically_normal().string();
    }
    for (auto it = node.begin(); it != node.end(); ++it) absolutize_meshes(it->second, dir);
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) absolutize_meshes(node[i], dir);
  }
}

}  // namespace

std::string wedge_scene_text(const std::string& scene_text, const std::vector<std::pair<std::string, std::string>>& set,
                             const std::string& scene_dir) {
  YAML::Node root = YAML::Load(scene_text);
  for (const auto& [key, value] : set) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    while (start <= key.size()) {
      const std::size_t dot = std::min(key.find('.', start), key.size());
      parts.push_back(key.substr(start, dot - start));
      start = dot + 1;
    }
    // yaml-cpp: `=` between nodes assigns content; reset() moves the handle.
    YAML::Node node = root;
    for (std::size_t k = 0; k + 1 < parts.size(); ++k) {
      const std::string& p = parts[k];
      if (node.IsSequence()) {
        bool found = false;
        for (std::size_t i = 0; i < node.size() && !found; ++i) {
          if (node[i].IsMap() && node[i]["name"] && node[i]["name"].as<std::string>() == p) {
            node.reset(node[i]);
            found = true;
          }
        }
        if (!found && !p.empty() && p.size() < 9 && p.find_first_not_of("0123456789") == std::string::npos &&
            std::stoul(p) < node.size()) {
          node.reset(node[std::stoul(p)]);
          found = true;
        }
        if (!found) throw std::runtime_error("wedge key " + key + ": no list element named '" + p + "'");
      } else if (node.IsMap() || node.IsNull()) {
        // A missing mapping on the way is created (e.g. magnetics in a scene without one).
        if (!node[p]) node[p] = YAML::Node(YAML::NodeType::Map);
        YAML::Node child = node[p];
        node.reset(child);
      } else {
        throw std::runtime_error("wedge key " + key + ": '" + p + "' is not inside a mapping or list");
      }
    }
    if (!(node.IsMap() || node.IsNull())) throw std::runtime_error("wedge key " + key + ": its parent is not a mapping");
    node[parts.back()] = YAML::Load(value);
  }
  absolutize_meshes(root, scene_dir);
  YAML::Emitter out;
  out << root;
  return std::string(out.c_str()) + "\n";
}

std::string wedge_folder_name(int index, const std::vector<std::pair<std::string, std::string>>& set) {
  std::string name = fmt::format("{:03d}", index);
  for (const auto& [key, value] : set) name += "_" + key + "=" + value;
  for (char& c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
                    c == '=' || c == '-';
    if (!ok) c = '_';
  }
  return name;
}

}  // namespace magbake::cli
