#include "yaml_params.h"

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <regex>
#include <sstream>

namespace laser_raycast {
namespace {

// PyYAML's implicit resolvers for YAML 1.1 (yaml/resolver.py), which rosparam uses.
const std::regex kBool(
    "yes|Yes|YES|no|No|NO|true|True|TRUE|false|False|FALSE|on|On|ON|off|Off|OFF");
const std::regex kInt(
    "[-+]?0b[0-1_]+|[-+]?0[0-7_]+|[-+]?(?:0|[1-9][0-9_]*)|[-+]?0x[0-9a-fA-F_]+"
    "|[-+]?[1-9][0-9_]*(?::[0-5]?[0-9])+");
const std::regex kFloat(
    "[-+]?(?:[0-9][0-9_]*)\\.[0-9_]*(?:[eE][-+][0-9]+)?|\\.[0-9_]+(?:[eE][-+][0-9]+)?"
    "|[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+\\.[0-9_]*|[-+]?\\.(?:inf|Inf|INF)|\\.(?:nan|NaN|NAN)");

const std::string kTagPrefix = "tag:yaml.org,2002:";

// Where a node is, for messages: "source:line:column" (from 1).
std::string where(const std::string& source, const YAML::Mark& mark) {
  if (mark.is_null()) return source;
  return source + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
}

// A parameter's path ("sensors[1]/rate"), for messages.
std::string child(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "/" + key;
}

// The sign and the digits of a YAML 1.1 number, '_' removed.
struct Digits {
  bool negative = false;
  std::string text;
};

Digits digitsOf(const std::string& scalar) {
  Digits d;
  std::size_t i = 0;
  if (!scalar.empty() && (scalar[0] == '-' || scalar[0] == '+')) {
    d.negative = scalar[0] == '-';
    i = 1;
  }
  for (; i < scalar.size(); ++i) {
    if (scalar[i] != '_') d.text += scalar[i];
  }
  return d;
}

// The value of a base-60 number "a:b:c" (a may be large, the others below 60), digits already
// without sign and '_'.
double sexagesimal(const std::string& text) {
  double value = 0;
  std::istringstream parts(text);
  std::string part;
  while (std::getline(parts, part, ':')) value = value * 60 + std::strtod(part.c_str(), nullptr);
  return value;
}

// An int scalar as PyYAML reads it; nullopt beyond the 32 bits of an XmlRpc int.
std::optional<int> toInt(const std::string& scalar) {
  const Digits d = digitsOf(scalar);
  long double magnitude;
  if (d.text.find(':') != std::string::npos) {
    magnitude = sexagesimal(d.text);
  } else {
    int base = 10;
    std::size_t skip = 0;
    if (d.text.rfind("0b", 0) == 0) {
      base = 2, skip = 2;
    } else if (d.text.rfind("0x", 0) == 0) {
      base = 16, skip = 2;
    } else if (d.text.size() > 1 && d.text[0] == '0') {
      base = 8, skip = 1;
    }
    errno = 0;
    const unsigned long long u = std::strtoull(d.text.c_str() + skip, nullptr, base);
    if (errno == ERANGE) return std::nullopt;
    magnitude = static_cast<long double>(u);
  }
  const long double value = d.negative ? -magnitude : magnitude;
  if (value < std::numeric_limits<int>::min() || value > std::numeric_limits<int>::max()) {
    return std::nullopt;
  }
  return static_cast<int>(value);
}

double toDouble(const std::string& scalar) {
  const Digits d = digitsOf(scalar);
  double magnitude;
  if (d.text.find("inf") != std::string::npos || d.text.find("Inf") != std::string::npos ||
      d.text.find("INF") != std::string::npos) {
    magnitude = std::numeric_limits<double>::infinity();
  } else if (d.text.find_first_of("nN") != std::string::npos) {
    magnitude = std::numeric_limits<double>::quiet_NaN();
  } else if (d.text.find(':') != std::string::npos) {
    magnitude = sexagesimal(d.text);
  } else {
    magnitude = std::strtod(d.text.c_str(), nullptr);
  }
  return d.negative ? -magnitude : magnitude;
}

// What a scalar resolves to: its tag's type, or for a plain one ('?') PyYAML's implicit type.
std::string scalarType(const YAML::Node& node) {
  const std::string& tag = node.Tag();
  if (tag == "!") return "str";  // quoted
  if (tag == "?") {
    const std::string& s = node.Scalar();
    if (std::regex_match(s, kBool)) return "bool";
    if (std::regex_match(s, kInt)) return "int";
    if (std::regex_match(s, kFloat)) return "float";
    return "str";
  }
  if (tag.rfind(kTagPrefix, 0) == 0) return tag.substr(kTagPrefix.size());
  return tag;
}

XmlRpc::XmlRpcValue convert(const YAML::Node& node, const std::string& source,
                            const std::string& path);

XmlRpc::XmlRpcValue convertScalar(const YAML::Node& node, const std::string& source,
                                  const std::string& path) {
  const std::string& s = node.Scalar();
  const std::string type = scalarType(node);
  const auto fail = [&](const std::string& what) {
    return YamlParamsError(where(source, node.Mark()) + ": " + path + ": " + what);
  };
  if (type == "str") return XmlRpc::XmlRpcValue(s);
  if (type == "bool") {
    if (!std::regex_match(s, kBool)) throw fail("'" + s + "' is not a boolean");
    const char c = s[0];
    return XmlRpc::XmlRpcValue(c == 'y' || c == 'Y' || c == 't' || c == 'T' || s == "on" ||
                               s == "On" || s == "ON");
  }
  if (type == "int") {
    if (!std::regex_match(s, kInt)) throw fail("'" + s + "' is not an integer");
    const std::optional<int> value = toInt(s);
    if (!value) throw fail(s + " is beyond the 32-bit integers the parameter server holds");
    return XmlRpc::XmlRpcValue(*value);
  }
  if (type == "float") {
    // !!float also takes an integer's digits.
    if (!std::regex_match(s, kFloat) && !std::regex_match(s, kInt)) {
      throw fail("'" + s + "' is not a number");
    }
    return XmlRpc::XmlRpcValue(toDouble(s));
  }
  throw fail("the tag " + node.Tag() + " is not one the parameter server takes");
}

XmlRpc::XmlRpcValue convert(const YAML::Node& node, const std::string& source,
                            const std::string& path) {
  const std::string& tag = node.Tag();
  const bool tag_ok = tag == "?" || tag == "!" || tag.empty() || tag.rfind(kTagPrefix, 0) == 0;
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return convertScalar(node, source, path);
    case YAML::NodeType::Sequence: {
      if (!tag_ok || (tag.rfind(kTagPrefix, 0) == 0 && tag != kTagPrefix + "seq")) break;
      XmlRpc::XmlRpcValue out;
      out.setSize(static_cast<int>(node.size()));
      for (std::size_t i = 0; i < node.size(); ++i) {
        out[static_cast<int>(i)] = convert(node[i], source, path + "[" + std::to_string(i) + "]");
      }
      return out;
    }
    case YAML::NodeType::Map: {
      if (!tag_ok || (tag.rfind(kTagPrefix, 0) == 0 && tag != kTagPrefix + "map")) break;
      XmlRpc::XmlRpcValue out;
      out.begin();  // an empty mapping is an empty struct, not an invalid value
      for (auto it = node.begin(); it != node.end(); ++it) {
        if (!it->first.IsScalar()) {
          throw YamlParamsError(where(source, it->first.Mark()) + ": " + path +
                                ": a key that is not a scalar");
        }
        const std::string key = it->first.Scalar();
        out[key] = convert(it->second, source, child(path, key));
      }
      return out;
    }
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined:
      throw YamlParamsError(where(source, node.Mark()) + ": " + path +
                            ": has no value (null), which the parameter server cannot hold");
  }
  throw YamlParamsError(where(source, node.Mark()) + ": " + path + ": the tag " + tag +
                        " is not one the parameter server takes");
}

}  // namespace

XmlRpc::XmlRpcValue parseYamlParams(const std::string& text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw YamlParamsError(where(source, e.mark) + ": not YAML: " + e.msg);
  }
  if (!root.IsMap()) {
    throw YamlParamsError(source +
                          ": the top level must be a mapping of parameter names to values");
  }
  return convert(root, source, "");
}

XmlRpc::XmlRpcValue loadYamlParams(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    throw YamlParamsError(path + ": is a directory, not a YAML file");
  }
  std::ifstream in(path);
  if (!in) throw YamlParamsError(path + ": cannot be read (" + std::strerror(errno) + ")");
  std::ostringstream text;
  text << in.rdbuf();  // an empty file reads nothing, and is refused as not a mapping
  return parseYamlParams(text.str(), path);
}

}  // namespace laser_raycast
