// A USD layer as magbake writes it: prims with attributes (a default value or time samples),
// relationships and a little metadata, written as USDA text or as a binary USDC ("crate") file.
// Only what `magbake export --usd` needs; no USD library is packaged for Debian, so both
// formats are written here and checked against the reference implementation (usd-core) in tests.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace magbake::usd {

struct Token {
  std::string text;
};
struct Asset {
  std::string path;  ///< as written between @...@ (layer-relative or absolute)
};
using Vec3d = std::array<double, 3>;
using Vec3f = std::array<float, 3>;
struct Quatd {
  double w = 1, x = 0, y = 0, z = 0;
};

/// A value of one of the attribute types magbake writes (the USD type name is on the attribute).
using Value = std::variant<bool, int, float, double, std::string, Token, Asset, Vec3d, Quatd, std::vector<Token>,
                           std::vector<int>, std::vector<float>, std::vector<Vec3f>>;

struct Attribute {
  Attribute(std::string name_, std::string type, bool custom_ = false, bool uniform_ = false, std::optional<Value> v = {})
      : name(std::move(name_)), type_name(std::move(type)), custom(custom_), uniform(uniform_), value(std::move(v)) {}
  std::string name;       ///< e.g. "xformOp:translate"
  std::string type_name;  ///< USD value type name: "double3", "quatd", "token[]", "point3f[]", ...
  bool custom = false;
  bool uniform = false;
  std::optional<Value> value;                        ///< default value
  std::vector<std::pair<double, Value>> samples;      ///< time samples (time code, value), ascending
  std::string interpolation;                          ///< primvar interpolation metadata ("" = none)
};

struct Relationship {
  std::string name;
  std::vector<std::string> targets;  ///< absolute prim paths
};

struct Prim {
  Prim(std::string name_, std::string type, std::string kind_ = "")
      : name(std::move(name_)), type_name(std::move(type)), kind(std::move(kind_)) {}
  std::string name;       ///< a valid identifier
  std::string type_name;  ///< "Xform", "Mesh", ...
  std::string kind;       ///< "" = none
  std::string doc;        ///< "" = none
  std::vector<std::pair<std::string, std::string>> custom_data;  ///< string entries of customData
  std::vector<Attribute> attributes;
  std::vector<Relationship> relationships;
  std::vector<Prim> children;
};

struct Layer {
  std::string default_prim, doc, up_axis = "Z";
  double start = 0, end = 0, fps = 24, meters_per_unit = 1;
  std::vector<Prim> prims;
};

/// The layer as USDA 1.0 text (doubles with 17 significant digits, floats with 9: exact).
std::string to_usda(const Layer& layer);

/// The layer as a USDC (crate) file, format version 0.8.0 (USD's own default for new files; the
/// structural sections in USD's integer coding and LZ4 framing, stored rather than compressed,
/// arrays uncompressed).
std::vector<char> to_usdc(const Layer& layer);

}  // namespace magbake::usd
