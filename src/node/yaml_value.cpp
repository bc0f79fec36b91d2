#include "yaml_value.h"

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstdlib>
#include <limits>
#include <regex>

namespace laser_raycast {
namespace {

// Plain scalars as YAML 1.2's core schema types them.
const std::regex kBool("true|True|TRUE|false|False|FALSE");
const std::regex kInteger("[-+]?[0-9]+");
const std::regex kDecimal("[-+]?(\\.[0-9]+|[0-9]+(\\.[0-9]*)?)([eE][-+]?[0-9]+)?");
const std::regex kInfinity("[-+]?\\.(inf|Inf|INF)");
const std::regex kNotANumber("\\.(nan|NaN|NAN)");

// `where` names the place in the text for messages: "[1]", "[0]/frame_id"; empty at the top.
bool toScalar(const YAML::Node& node, const std::string& where, XmlRpc::XmlRpcValue* out,
              std::string* error) {
  const std::string& text = node.Scalar();
  // yaml-cpp tags a plain scalar "?"; a quoted one "!", one tagged !!str with the full tag.
  if (node.Tag() != "?") {
    *out = text;
  } else if (std::regex_match(text, kBool)) {
    *out = text[0] == 't' || text[0] == 'T';
  } else if (std::regex_match(text, kInteger)) {
    errno = 0;
    const long long integer = std::strtoll(text.c_str(), nullptr, 10);
    if (errno == ERANGE || integer < std::numeric_limits<int>::min() ||
        integer > std::numeric_limits<int>::max()) {
      *error = where + " is the integer " + text + ", beyond a parameter's int32 range";
      return false;
    }
    *out = static_cast<int>(integer);
  } else if (std::regex_match(text, kDecimal)) {
    *out = std::strtod(text.c_str(), nullptr);
  } else if (std::regex_match(text, kInfinity)) {
    *out = text[0] == '-' ? -std::numeric_limits<double>::infinity()
                          : std::numeric_limits<double>::infinity();
  } else if (std::regex_match(text, kNotANumber)) {
    *out = std::numeric_limits<double>::quiet_NaN();
  } else {
    *out = text;
  }
  return true;
}

bool toValue(const YAML::Node& node, const std::string& where, XmlRpc::XmlRpcValue* out,
             std::string* error) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      return toScalar(node, where, out, error);
    case YAML::NodeType::Sequence: {
      out->setSize(static_cast<int>(node.size()));
      for (std::size_t i = 0; i < node.size(); ++i) {
        const std::string at = where + "[" + std::to_string(i) + "]";
        if (!toValue(node[i], at, &(*out)[static_cast<int>(i)], error)) return false;
      }
      return true;
    }
    case YAML::NodeType::Map: {
      out->begin();  // an empty struct, also without entries
      for (const auto& entry : node) {
        if (!entry.first.IsScalar()) {
          *error = (where.empty() ? "a key" : "a key in " + where) + " is not a scalar";
          return false;
        }
        const std::string& key = entry.first.Scalar();
        const std::string at = where.empty() ? key : where + "/" + key;
        if (!toValue(entry.second, at, &(*out)[key], error)) return false;
      }
      return true;
    }
    default:
      *error = where + " is null, which no parameter can hold";
      return false;
  }
}

}  // namespace

bool parseYamlContainer(const std::string& text, XmlRpc::XmlRpcValue* value, std::string* error) {
  error->clear();
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    *error = "line " + std::to_string(e.mark.line + 1) + ", column " +
             std::to_string(e.mark.column + 1) + ": " + e.msg;
    return false;
  }
  if (!root.IsSequence() && !root.IsMap()) return false;
  XmlRpc::XmlRpcValue parsed;
  if (!toValue(root, "", &parsed, error)) return false;
  *value = parsed;
  return true;
}

}  // namespace laser_raycast
