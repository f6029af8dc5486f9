#include "usd_layer.h"

#include <fmt/format.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <sstream>

namespace magbake::usd {
namespace {

// ---------------------------------------------------------------------------------------------
// USDA

std::string quoted(const std::string& s) {
  std::string out(1, '"');
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  out.push_back('"');
  return out;
}

std::string num(double v) { return fmt::format("{:.17g}", v); }
std::string num(float v) { return fmt::format("{:.9g}", v); }
std::string time_code(double t) { return t == std::floor(t) && std::abs(t) < 1e15 ? fmt::format("{}", std::int64_t(t)) : num(t); }

template <class T, class F>
std::string list(const std::vector<T>& v, F item) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + item(v[i]);
  return s + "]";
}

std::string text(const Value& value) {
  struct Visit {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(int i) const { return fmt::format("{}", i); }
    std::string operator()(float f) const { return num(f); }
    std::string operator()(double d) const { return num(d); }
    std::string operator()(const std::string& s) const { return quoted(s); }
    std::string operator()(const Token& t) const { return quoted(t.text); }
    std::string operator()(const Asset& a) const { return "@" + a.path + "@"; }
    std::string operator()(const Vec3d& v) const { return fmt::format("({}, {}, {})", num(v[0]), num(v[1]), num(v[2])); }
    std::string operator()(const Quatd& q) const {
      return fmt::format("({}, {}, {}, {})", num(q.w), num(q.x), num(q.y), num(q.z));
    }
    std::string operator()(const std::vector<Token>& v) const { return list(v, [](const Token& t) { return quoted(t.text); }); }
    std::string operator()(const std::vector<int>& v) const { return list(v, [](int i) { return fmt::format("{}", i); }); }
    std::string operator()(const std::vector<float>& v) const { return list(v, [](float f) { return num(f); }); }
    std::string operator()(const std::vector<Vec3f>& v) const {
      return list(v, [](const Vec3f& p) { return fmt::format("({}, {}, {})", num(p[0]), num(p[1]), num(p[2])); });
    }
  };
  return std::visit(Visit{}, value);
}

void write_prim(std::ostringstream& o, const Prim& p, const std::string& indent) {
  o << indent << "def " << p.type_name << " " << quoted(p.name);
  if (!p.kind.empty() || !p.doc.empty() || !p.custom_data.empty()) {
    o << " (\n";
    if (!p.custom_data.empty()) {
      o << indent << "    customData = {\n";
      for (const auto& [k, v] : p.custom_data) o << indent << "        string " << k << " = " << quoted(v) << "\n";
      o << indent << "    }\n";
    }
    if (!p.doc.empty()) o << indent << "    doc = " << quoted(p.doc) << "\n";
    if (!p.kind.empty()) o << indent << "    kind = " << quoted(p.kind) << "\n";
    o << indent << ")";
  }
  o << "\n" << indent << "{\n";
  const std::string in = indent + "    ";
  for (const Attribute& a : p.attributes) {
    const std::string decl = fmt::format("{}{}{}{} {}", in, a.custom ? "custom " : "", a.uniform ? "uniform " : "", a.type_name, a.name);
    const std::string meta = a.interpolation.empty() ? "" : fmt::format(" (\n{}    interpolation = {}\n{})", in, quoted(a.interpolation), in);
    if (a.value) {
      o << decl << " = " << text(*a.value) << meta << "\n";
    } else if (!meta.empty() || a.samples.empty()) {
      o << decl << meta << "\n";
    }
    if (!a.samples.empty()) {
      o << decl << ".timeSamples = {\n";
      for (const auto& [t, v] : a.samples) o << in << "    " << time_code(t) << ": " << text(v) << ",\n";
      o << in << "}\n";
    }
  }
  for (const Relationship& r : p.relationships) {
    o << in << "rel " << r.name << " = ";
    if (r.targets.size() == 1) o << "<" << r.targets[0] << ">\n";
    else o << list(r.targets, [](const std::string& t) { return "<" + t + ">"; }) << "\n";
  }
  for (std::size_t c = 0; c < p.children.size(); ++c) {
    if (c || !p.attributes.empty() || !p.relationships.empty()) o << "\n";
    write_prim(o, p.children[c], in);
  }
  o << indent << "}\n";
}

// ---------------------------------------------------------------------------------------------
// USDC (the "crate" format of pxr/usd/sdf/crateFile.cpp), version 0.8.0 (what USD itself writes
// by default): a bootstrap header, the values, then six structural sections (tokens, strings, fields,
// field sets, paths, specs) and a table of contents. Every value is a 64-bit ValueRep: type (bits 48-55), array
// (63) and inlined (62) flags, and a 48-bit payload (the value itself, an index into the token,
// string or path table, or the file offset of the value's data).

// TfFastCompression's framing (a zero byte: one chunk) around an LZ4 block. The block holds one
// literal run (valid LZ4 that any decoder reads; magbake does not compress: the values, which
// hold nearly all the bytes, are stored uncompressed in the format anyway).
std::vector<char> lz4_stored(const char* data, std::size_t n) {
  std::vector<char> out{0};
  out.push_back(char(std::min<std::size_t>(n, 15) << 4));
  if (n >= 15) {
    std::size_t rest = n - 15;
    for (; rest >= 255; rest -= 255) out.push_back(char(255));
    out.push_back(char(rest));
  }
  out.insert(out.end(), data, data + n);
  return out;
}

// Sdf_IntegerCompression (pxr/usd/sdf/integerCoding.cpp): differences to the previous value, a
// "common" value, 2-bit codes (3: a 32-bit difference follows, used for every value here), then
// the TfFastCompression framing.
std::vector<char> compressed_ints(const std::vector<std::int32_t>& v) {
  std::vector<char> enc(4 + (v.size() * 2 + 7) / 8, 0);
  for (std::size_t i = 0; i < v.size(); ++i) enc[4 + i / 4] = char(std::uint8_t(enc[4 + i / 4]) | (3u << (2 * (i % 4))));
  std::int32_t prev = 0;
  for (std::int32_t x : v) {
    const std::int32_t d = std::int32_t(std::uint32_t(x) - std::uint32_t(prev));
    const char* p = reinterpret_cast<const char*>(&d);
    enc.insert(enc.end(), p, p + 4);
    prev = x;
  }
  return lz4_stored(enc.data(), enc.size());
}

enum class Type : std::uint64_t {
  Bool = 1, Int = 3, Float = 8, Double = 9, String = 10, Token = 11, AssetPath = 12, Quatd = 16, Vec3d = 23, Vec3f = 24,
  Dictionary = 31, PathListOp = 34, TokenVector = 41, Specifier = 42, Variability = 44, TimeSamples = 46, DoubleVector = 48,
};
enum SpecType : std::uint32_t { kAttribute = 1, kPrim = 6, kPseudoRoot = 7, kRelationship = 8 };
constexpr std::uint64_t kArray = 1ull << 63, kInlined = 1ull << 62;

std::uint64_t rep(Type t, std::uint64_t payload, bool inlined, bool array = false) {
  return (array ? kArray : 0) | (inlined ? kInlined : 0) | (std::uint64_t(t) << 48) | (payload & ((1ull << 48) - 1));
}

class Crate {
 public:
  std::vector<char> out;

  Crate() { out.resize(88); }  // the bootstrap, written last

  template <class T>
  void put(const T& v) {
    const char* p = reinterpret_cast<const char*>(&v);
    out.insert(out.end(), p, p + sizeof(T));
  }
  template <class T>
  void put_at(std::size_t at, const T& v) {
    std::memcpy(out.data() + at, &v, sizeof(T));
  }
  void align8() { out.resize((out.size() + 7) / 8 * 8, 0); }

  std::uint32_t token(const std::string& s) {
    auto [it, added] = token_index_.emplace(s, std::uint32_t(tokens_.size()));
    if (added) tokens_.push_back(s);
    return it->second;
  }
  std::uint32_t string(const std::string& s) {
    auto [it, added] = string_index_.emplace(s, std::uint32_t(strings_.size()));
    if (added) strings_.push_back(token(s));
    return it->second;
  }
  std::uint32_t path(const std::string& p) {
    auto [it, added] = path_index_.emplace(p, std::uint32_t(paths_.size()));
    if (added) paths_.push_back(p);
    return it->second;
  }

  // A value's rep, its data (if any) appended to the file now.
  std::uint64_t pack(const Value& value) {
    struct Visit {
      Crate& c;
      std::uint64_t operator()(bool b) const { return rep(Type::Bool, b ? 1 : 0, true); }
      std::uint64_t operator()(int i) const { return rep(Type::Int, std::uint32_t(i), true); }
      std::uint64_t operator()(float f) const {
        std::uint32_t bits;
        std::memcpy(&bits, &f, 4);
        return rep(Type::Float, bits, true);
      }
      std::uint64_t operator()(double d) const { return c.scalar(Type::Double, d); }
      std::uint64_t operator()(const std::string& s) const { return rep(Type::String, c.string(s), true); }
      std::uint64_t operator()(const Token& t) const { return rep(Type::Token, c.token(t.text), true); }
      std::uint64_t operator()(const Asset& a) const { return rep(Type::AssetPath, c.token(a.path), true); }
      std::uint64_t operator()(const Vec3d& v) const { return c.scalar(Type::Vec3d, v); }
      std::uint64_t operator()(const Quatd& q) const {
        const std::array<double, 4> g{q.x, q.y, q.z, q.w};  // GfQuatd: imaginary part, then real
        return c.scalar(Type::Quatd, g);
      }
      std::uint64_t operator()(const std::vector<Token>& v) const {
        std::vector<std::uint32_t> ix;
        for (const Token& t : v) ix.push_back(c.token(t.text));
        return c.array(Type::Token, ix);
      }
      std::uint64_t operator()(const std::vector<int>& v) const { return c.array(Type::Int, v); }
      std::uint64_t operator()(const std::vector<float>& v) const { return c.array(Type::Float, v); }
      std::uint64_t operator()(const std::vector<Vec3f>& v) const { return c.array(Type::Vec3f, v); }
    };
    return std::visit(Visit{*this}, value);
  }
  template <class T>
  std::uint64_t scalar(Type t, const T& v) {
    const std::size_t at = out.size();
    put(v);
    return rep(t, at, false);
  }
  // Arrays (0.7.0 on, stored uncompressed): aligned to 8, a 64-bit count, the elements; an empty
  // array is a rep with payload 0.
  template <class T>
  std::uint64_t array(Type t, const std::vector<T>& v) {
    if (v.empty()) return rep(t, 0, false, true);
    align8();
    const std::size_t at = out.size();
    put(std::uint64_t(v.size()));
    const char* p = reinterpret_cast<const char*>(v.data());
    out.insert(out.end(), p, p + v.size() * sizeof(T));
    return rep(t, at, false, true);
  }
  std::uint64_t token_vector(const std::vector<std::string>& v) {
    const std::size_t at = out.size();
    put(std::uint64_t(v.size()));
    for (const std::string& s : v) put(token(s));
    return rep(Type::TokenVector, at, false);
  }
  // customData: a dictionary of strings (each value a VtValue: a forward offset, then its rep).
  std::uint64_t dictionary(const std::vector<std::pair<std::string, std::string>>& d) {
    const std::size_t at = out.size();
    put(std::uint64_t(d.size()));
    for (const auto& [k, v] : d) {
      put(string(k));
      put(std::int64_t(8));  // the value's data would lie between this offset and its rep: none
      put(rep(Type::String, string(v), true));
    }
    return rep(Type::Dictionary, at, false);
  }
  // An explicit list of paths: the list-op header (explicit, has explicit items), then them.
  std::uint64_t path_list(const std::vector<std::string>& targets) {
    const std::size_t at = out.size();
    put(std::uint8_t(1 | 2));
    put(std::uint64_t(targets.size()));
    for (const std::string& t : targets) put(path(t));
    return rep(Type::PathListOp, at, false);
  }
  // Time samples: a forward offset over the times' data, the times' rep (a vector of doubles),
  // a forward offset over the values' data, then the count and the values' reps.
  std::uint64_t time_samples(const std::vector<std::pair<double, Value>>& samples) {
    const std::size_t at = out.size();
    put(std::int64_t(0));
    const std::size_t times_at = out.size();
    put(std::uint64_t(samples.size()));
    for (const auto& s : samples) put(s.first);
    put_at(at, std::int64_t(out.size() - at));
    put(rep(Type::DoubleVector, times_at, false));
    const std::size_t values_jump = out.size();
    put(std::int64_t(0));
    std::vector<std::uint64_t> reps;
    for (const auto& s : samples) reps.push_back(pack(s.second));
    put_at(values_jump, std::int64_t(out.size() - values_jump));
    put(std::uint64_t(reps.size()));
    for (std::uint64_t r : reps) put(r);
    return rep(Type::TimeSamples, at, false);
  }

  // A spec with its fields (name, rep).
  void spec(const std::string& p, SpecType type, const std::vector<std::pair<std::string, std::uint64_t>>& fields) {
    const std::uint32_t set = std::uint32_t(field_sets_.size());
    for (const auto& [name, r] : fields) {
      field_sets_.push_back(std::uint32_t(fields_.size()));
      fields_.push_back({token(name), r});
    }
    field_sets_.push_back(0xffffffffu);
    specs_.push_back({path(p), set, type});
  }

  std::vector<char> finish();

 private:
  struct Field {
    std::uint32_t token;
    std::uint64_t rep;
  };
  struct Spec {
    std::uint32_t path, field_set, type;
  };
  struct Node {
    std::uint32_t index = 0, token = 0;
    bool property = false;
    std::vector<std::size_t> children;
  };

  std::vector<std::string> tokens_, paths_;
  std::vector<std::uint32_t> strings_, field_sets_;
  std::map<std::string, std::uint32_t> token_index_, string_index_, path_index_;
  std::vector<Field> fields_;
  std::vector<Spec> specs_;
};

std::vector<char> Crate::finish() {
  // Path tree: every path under its parent ("/a/b.c": property c of prim /a/b).
  std::vector<Node> nodes(1);
  std::map<std::string, std::size_t> node_of{{"/", 0}};
  nodes[0].token = token("");  // the root's element
  for (std::size_t i = 0; i < paths_.size(); ++i) {
    const std::string& p = paths_[i];
    if (p == "/") {
      nodes[0].index = std::uint32_t(i);
      continue;
    }
    // Walk down creating nodes (every prefix of a path we write is itself a written path here).
    const std::size_t dot = p.find('.');
    const std::string prim = dot == std::string::npos ? p : p.substr(0, dot);
    std::size_t parent = 0;
    std::size_t start = 1;
    while (start <= prim.size()) {
      const std::size_t end = std::min(prim.find('/', start), prim.size());
      const std::string prefix = prim.substr(0, end);
      auto it = node_of.find(prefix);
      if (it == node_of.end()) {
        Node nd;
        nd.index = path(prefix);
        nd.token = token(prim.substr(start, end - start));
        nodes.push_back(nd);
        it = node_of.emplace(prefix, nodes.size() - 1).first;
        nodes[parent].children.push_back(it->second);
      }
      parent = it->second;
      start = end + 1;
    }
    if (dot != std::string::npos && !node_of.count(p)) {
      Node nd;
      nd.index = path(p);
      nd.token = token(p.substr(dot + 1));
      nd.property = true;
      nodes.push_back(nd);
      node_of.emplace(p, nodes.size() - 1);
      nodes[parent].children.push_back(nodes.size() - 1);
    }
  }

  struct Section {
    char name[16];
    std::int64_t start, size;
  };
  std::vector<Section> toc;
  auto section = [&](const char* name, auto&& body) {
    Section s{};
    std::strncpy(s.name, name, 15);
    s.start = std::int64_t(out.size());
    body();
    s.size = std::int64_t(out.size()) - s.start;
    toc.push_back(s);
  };
  auto put_ints = [&](const std::vector<std::int32_t>& v) {
    const std::vector<char> c = compressed_ints(v);
    put(std::uint64_t(c.size()));
    out.insert(out.end(), c.begin(), c.end());
  };
  section("TOKENS", [&] {
    put(std::uint64_t(tokens_.size()));
    std::vector<char> chars;
    for (const std::string& t : tokens_) chars.insert(chars.end(), t.c_str(), t.c_str() + t.size() + 1);
    const std::vector<char> c = lz4_stored(chars.data(), chars.size());
    put(std::uint64_t(chars.size()));
    put(std::uint64_t(c.size()));
    out.insert(out.end(), c.begin(), c.end());
  });
  section("STRINGS", [&] {
    put(std::uint64_t(strings_.size()));
    for (std::uint32_t s : strings_) put(s);
  });
  section("FIELDS", [&] {
    put(std::uint64_t(fields_.size()));
    std::vector<std::int32_t> names;
    std::vector<std::uint64_t> reps;
    for (const Field& f : fields_) names.push_back(std::int32_t(f.token)), reps.push_back(f.rep);
    put_ints(names);
    const std::vector<char> c = lz4_stored(reinterpret_cast<const char*>(reps.data()), reps.size() * 8);
    put(std::uint64_t(c.size()));
    out.insert(out.end(), c.begin(), c.end());
  });
  section("FIELDSETS", [&] {
    put(std::uint64_t(field_sets_.size()));
    put_ints(std::vector<std::int32_t>(field_sets_.begin(), field_sets_.end()));
  });
  section("PATHS", [&] {
    // The path tree in preorder: each item's path index, element token (negated for a
    // property) and jump: -2 a leaf, -1 a child follows and no sibling, 0 a sibling follows and
    // no child, > 0 a child follows and the sibling is that many items on.
    std::vector<bool> has_sibling(nodes.size(), false);
    std::vector<std::size_t> next_sibling(nodes.size(), 0);
    for (const Node& nd : nodes) {
      for (std::size_t k = 0; k + 1 < nd.children.size(); ++k) {
        has_sibling[nd.children[k]] = true;
        next_sibling[nd.children[k]] = nd.children[k + 1];
      }
    }
    std::vector<std::int32_t> index, element, jump;
    std::vector<std::size_t> item_of(nodes.size(), 0);
    std::vector<std::size_t> stack{0};
    while (!stack.empty()) {
      const std::size_t n = stack.back();
      stack.pop_back();
      const Node& nd = nodes[n];
      item_of[n] = index.size();
      index.push_back(std::int32_t(nd.index));
      element.push_back(nd.property ? -std::int32_t(nd.token) : std::int32_t(nd.token));
      const bool child = !nd.children.empty(), sibling = has_sibling[n];
      jump.push_back(child && sibling ? 1 : sibling ? 0 : child ? -1 : -2);  // sibling distance patched below
      if (sibling) stack.push_back(next_sibling[n]);
      if (child) stack.push_back(nd.children.front());
    }
    for (std::size_t n = 0; n < nodes.size(); ++n) {
      if (!nodes[n].children.empty() && has_sibling[n]) {
        jump[item_of[n]] = std::int32_t(item_of[next_sibling[n]] - item_of[n]);
      }
    }
    put(std::uint64_t(paths_.size()));
    put(std::uint64_t(index.size()));
    put_ints(index);
    put_ints(element);
    put_ints(jump);
  });
  section("SPECS", [&] {
    put(std::uint64_t(specs_.size()));
    std::vector<std::int32_t> path, set, type;
    for (const Spec& sp : specs_) path.push_back(std::int32_t(sp.path)), set.push_back(std::int32_t(sp.field_set)), type.push_back(std::int32_t(sp.type));
    put_ints(path);
    put_ints(set);
    put_ints(type);
  });
  const std::int64_t toc_at = std::int64_t(out.size());
  put(std::uint64_t(toc.size()));
  for (const Section& s : toc) put(s);
  // Bootstrap: identifier, version 0.8.0, offset of the table of contents, 8 reserved words.
  std::memcpy(out.data(), "PXR-USDC", 8);
  const std::uint8_t version[8] = {0, 8, 0, 0, 0, 0, 0, 0};
  std::memcpy(out.data() + 8, version, 8);
  put_at(16, toc_at);
  return std::move(out);
}

void pack_prim(Crate& c, const Prim& p, const std::string& parent) {
  const std::string path = parent == "/" ? "/" + p.name : parent + "/" + p.name;
  std::vector<std::pair<std::string, std::uint64_t>> fields;
  fields.emplace_back("specifier", rep(Type::Specifier, 0, true));  // def
  fields.emplace_back("typeName", rep(Type::Token, c.token(p.type_name), true));
  if (!p.kind.empty()) fields.emplace_back("kind", rep(Type::Token, c.token(p.kind), true));
  if (!p.doc.empty()) fields.emplace_back("documentation", rep(Type::String, c.string(p.doc), true));
  if (!p.custom_data.empty()) fields.emplace_back("customData", c.dictionary(p.custom_data));
  std::vector<std::string> properties, children;
  for (const Attribute& a : p.attributes) properties.push_back(a.name);
  for (const Relationship& r : p.relationships) properties.push_back(r.name);
  for (const Prim& ch : p.children) children.push_back(ch.name);
  if (!properties.empty()) fields.emplace_back("properties", c.token_vector(properties));
  if (!children.empty()) fields.emplace_back("primChildren", c.token_vector(children));
  c.spec(path, kPrim, fields);
  for (const Attribute& a : p.attributes) {
    std::vector<std::pair<std::string, std::uint64_t>> af;
    af.emplace_back("typeName", rep(Type::Token, c.token(a.type_name), true));
    if (a.custom) af.emplace_back("custom", rep(Type::Bool, 1, true));
    if (a.uniform) af.emplace_back("variability", rep(Type::Variability, 1, true));
    if (!a.interpolation.empty()) af.emplace_back("interpolation", rep(Type::Token, c.token(a.interpolation), true));
    if (a.value) af.emplace_back("default", c.pack(*a.value));
    if (!a.samples.empty()) af.emplace_back("timeSamples", c.time_samples(a.samples));
    c.spec(path + "." + a.name, kAttribute, af);
  }
  for (const Relationship& r : p.relationships) {
    std::vector<std::pair<std::string, std::uint64_t>> rf;
    rf.emplace_back("variability", rep(Type::Variability, 1, true));
    rf.emplace_back("targetPaths", c.path_list(r.targets));
    c.spec(path + "." + r.name, kRelationship, rf);
  }
  for (const Prim& ch : p.children) pack_prim(c, ch, path);
}

}  // namespace

std::string to_usda(const Layer& l) {
  std::ostringstream o;
  o << "#usda 1.0\n(\n";
  o << "    defaultPrim = " << quoted(l.default_prim) << "\n";
  if (!l.doc.empty()) o << "    doc = " << quoted(l.doc) << "\n";
  o << "    endTimeCode = " << time_code(l.end) << "\n";
  o << "    framesPerSecond = " << num(l.fps) << "\n";
  o << "    metersPerUnit = " << num(l.meters_per_unit) << "\n";
  o << "    startTimeCode = " << time_code(l.start) << "\n";
  o << "    timeCodesPerSecond = " << num(l.fps) << "\n";
  o << "    upAxis = " << quoted(l.up_axis) << "\n)\n";
  for (const Prim& p : l.prims) {
    o << "\n";
    write_prim(o, p, "");
  }
  return o.str();
}

std::vector<char> to_usdc(const Layer& l) {
  Crate c;
  std::vector<std::pair<std::string, std::uint64_t>> root;
  root.emplace_back("defaultPrim", rep(Type::Token, c.token(l.default_prim), true));
  if (!l.doc.empty()) root.emplace_back("documentation", rep(Type::String, c.string(l.doc), true));
  root.emplace_back("endTimeCode", c.scalar(Type::Double, l.end));
  root.emplace_back("framesPerSecond", c.scalar(Type::Double, l.fps));
  root.emplace_back("metersPerUnit", c.scalar(Type::Double, l.meters_per_unit));
  root.emplace_back("startTimeCode", c.scalar(Type::Double, l.start));
  root.emplace_back("timeCodesPerSecond", c.scalar(Type::Double, l.fps));
  root.emplace_back("upAxis", rep(Type::Token, c.token(l.up_axis), true));
  std::vector<std::string> children;
  for (const Prim& p : l.prims) children.push_back(p.name);
  root.emplace_back("primChildren", c.token_vector(children));
  c.spec("/", kPseudoRoot, root);
  for (const Prim& p : l.prims) pack_prim(c, p, "/");
  return c.finish();
}

}  // namespace magbake::usd
