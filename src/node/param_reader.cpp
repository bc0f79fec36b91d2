#include "param_reader.h"

#include <array>
#include <charconv>
#include <sstream>
#include <utility>

#include "yaml_value.h"

namespace laser_raycast {

std::string formatNumber(double value) {
  // The shortest text that reads back as the same double, so that a logged value is exactly the
  // one in use (M_PI as 3.141592653589793, not 3.14159) and 0.1 is still 0.1.
  std::array<char, 32> buffer;
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}

std::string describeValue(const XmlRpc::XmlRpcValue& value) {
  using V = XmlRpc::XmlRpcValue;
  switch (value.getType()) {
    case V::TypeBoolean:
      return static_cast<const bool&>(value) ? "true" : "false";
    case V::TypeInt:
      return std::to_string(static_cast<const int&>(value));
    case V::TypeDouble:
      return formatNumber(static_cast<const double&>(value));
    case V::TypeString:
      return "'" + static_cast<const std::string&>(value) + "'";
    case V::TypeArray: {
      std::string out = "[";
      for (int i = 0; i < value.size(); ++i) out += (i ? ", " : "") + describeValue(value[i]);
      return out + "]";
    }
    case V::TypeStruct: {
      std::string out = "{";
      for (auto it = value.begin(); it != value.end(); ++it) {
        out += (it == value.begin() ? "" : ", ") + it->first + ": " + describeValue(it->second);
      }
      return out + "}";
    }
    default:
      return "<" + std::string(typeName(value.getType())) + ">";
  }
}

std::string joinFirst(const std::vector<std::string>& names, std::size_t n) {
  std::string out;
  for (std::size_t i = 0; i < names.size() && i < n; ++i) out += (i ? ", " : "") + names[i];
  if (names.size() > n) out += ", ... (" + std::to_string(names.size() - n) + " more)";
  return out;
}

const char* typeName(XmlRpc::XmlRpcValue::Type type) {
  switch (type) {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return "bool";
    case XmlRpc::XmlRpcValue::TypeInt:
      return "int";
    case XmlRpc::XmlRpcValue::TypeDouble:
      return "double";
    case XmlRpc::XmlRpcValue::TypeString:
      return "string";
    case XmlRpc::XmlRpcValue::TypeArray:
      return "list";
    case XmlRpc::XmlRpcValue::TypeStruct:
      return "dict";
    default:
      return "other";
  }
}

ParamReader::ParamReader(const XmlRpc::XmlRpcValue& values, std::string prefix)
    : values_(values), prefix_(std::move(prefix)) {
  const auto type = values_.getType();
  if (type != XmlRpc::XmlRpcValue::TypeStruct && type != XmlRpc::XmlRpcValue::TypeInvalid) {
    failWith("the namespace " + prefix_ + " holds a " + typeName(type) + " (" +
             describeValue(values_) + ") instead of parameters");
  }
}

bool ParamReader::has(const std::string& name) { return get(name) != nullptr; }

const XmlRpc::XmlRpcValue* ParamReader::get(const std::string& name) {
  if (known_.insert(name).second) known_order_.push_back(name);
  if (values_.getType() != XmlRpc::XmlRpcValue::TypeStruct) return nullptr;
  for (auto it = values_.begin(); it != values_.end(); ++it) {
    if (it->first == name) return &it->second;
  }
  return nullptr;
}

const XmlRpc::XmlRpcValue* ParamReader::container(const std::string& name, const char* expected) {
  const XmlRpc::XmlRpcValue* v = get(name);
  if (!v || v->getType() != XmlRpc::XmlRpcValue::TypeString) return v;
  XmlRpc::XmlRpcValue parsed;
  std::string error;
  if (parseYamlContainer(static_cast<const std::string&>(*v), &parsed, &error)) {
    return &(from_yaml_[name] = parsed);
  }
  if (error.empty()) return v;
  fail(name, "is a string (" + describeValue(*v) + ") that YAML cannot read as a parameter (" +
                 error + "), expected " + expected);
  return nullptr;
}

double ParamReader::number(const std::string& name, double fallback, const char* unit) {
  const double value =
      scalar<double>(name, fallback, "a number", [](const XmlRpc::XmlRpcValue& v, double* out) {
        if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
          *out = static_cast<const double&>(v);
        } else if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) {
          *out = static_cast<const int&>(v);
        } else {
          return false;
        }
        return true;
      });
  note(prefix_ + name + " = " + formatNumber(value) + (*unit ? " " : "") + unit);
  return value;
}

int ParamReader::integer(const std::string& name, int fallback, const char* unit) {
  const int value =
      scalar<int>(name, fallback, "an integer", [](const XmlRpc::XmlRpcValue& v, int* out) {
        if (v.getType() != XmlRpc::XmlRpcValue::TypeInt) return false;
        *out = static_cast<const int&>(v);
        return true;
      });
  note(prefix_ + name + " = " + std::to_string(value) + (*unit ? " " : "") + unit);
  return value;
}

bool ParamReader::boolean(const std::string& name, bool fallback) {
  const bool value =
      scalar<bool>(name, fallback, "true or false", [](const XmlRpc::XmlRpcValue& v, bool* out) {
        if (v.getType() != XmlRpc::XmlRpcValue::TypeBoolean) {
          return false;
        }
        *out = static_cast<const bool&>(v);
        return true;
      });
  note(prefix_ + name + " = " + (value ? "true" : "false"));
  return value;
}

std::string ParamReader::text(const std::string& name, const std::string& fallback) {
  const std::string value = scalar<std::string>(
      name, fallback, "a string", [](const XmlRpc::XmlRpcValue& v, std::string* out) {
        if (v.getType() != XmlRpc::XmlRpcValue::TypeString) return false;
        *out = static_cast<const std::string&>(v);
        return true;
      });
  note(prefix_ + name + " = '" + value + "'");
  return value;
}

std::vector<std::string> ParamReader::textList(const std::string& name) {
  std::vector<std::string> value;
  if (const XmlRpc::XmlRpcValue* v = container(name, "a list of strings")) {
    if (v->getType() != XmlRpc::XmlRpcValue::TypeArray) {
      wrongType(name, *v, "a list of strings");
    } else {
      for (int i = 0; i < v->size(); ++i) {
        const XmlRpc::XmlRpcValue& entry = (*v)[i];
        if (entry.getType() != XmlRpc::XmlRpcValue::TypeString) {
          wrongType(name + "[" + std::to_string(i) + "]", entry, "a string");
          break;
        }
        value.push_back(static_cast<const std::string&>(entry));
      }
    }
  }
  std::string shown;
  for (const std::string& s : value) shown += (shown.empty() ? "" : ", ") + s;
  note(prefix_ + name + " = [" + shown + "]");
  return value;
}

std::vector<double> ParamReader::numberList(const std::string& name,
                                            const std::vector<double>& fallback, const char* unit) {
  std::vector<double> value = fallback;
  if (const XmlRpc::XmlRpcValue* v = container(name, "a list of numbers")) {
    value.clear();
    if (v->getType() != XmlRpc::XmlRpcValue::TypeArray) {
      wrongType(name, *v, "a list of numbers");
    } else {
      for (int i = 0; i < v->size(); ++i) {
        const XmlRpc::XmlRpcValue& entry = (*v)[i];
        if (entry.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
          value.push_back(static_cast<const double&>(entry));
        } else if (entry.getType() == XmlRpc::XmlRpcValue::TypeInt) {
          value.push_back(static_cast<const int&>(entry));
        } else {
          wrongType(name + "[" + std::to_string(i) + "]", entry, "a number");
          break;
        }
      }
    }
  }
  std::string shown;
  for (const double x : value) shown += (shown.empty() ? "" : ", ") + formatNumber(x);
  note(prefix_ + name + " = [" + shown + "]" + (*unit ? " " : "") + unit);
  return value;
}

void ParamReader::fail(const std::string& name, const std::string& message) {
  failWith("parameter " + prefix_ + name + ": " + message);
}

void ParamReader::failWith(const std::string& message) {
  if (error_.empty()) error_ = message;
}

void ParamReader::wrongType(const std::string& name, const XmlRpc::XmlRpcValue& value,
                            const char* expected) {
  std::ostringstream msg;
  msg << "is a " << typeName(value.getType()) << " (" << describeValue(value) << "), expected "
      << expected;
  fail(name, msg.str());
}

std::vector<std::string> ParamReader::unknown() const {
  std::vector<std::string> names;
  if (values_.getType() != XmlRpc::XmlRpcValue::TypeStruct) return names;
  for (auto it = values_.begin(); it != values_.end(); ++it) {
    if (!known_.count(it->first)) names.push_back(it->first);
  }
  return names;
}

}  // namespace laser_raycast
