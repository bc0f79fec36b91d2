// Typed reading of one struct of parameter values, as the parameter server hands out a namespace
// (XmlRpc). Each read checks the type (a wrong type is an error, never a silent fall back to the
// default), remembers the name (keys never read are reported as unknown: usually typos), and adds
// one line with the value and its unit to the start-up log. The first error is kept.
#pragma once

#include <xmlrpcpp/XmlRpcValue.h>

#include <map>
#include <set>
#include <string>
#include <vector>

#include "laser_raycast/core/enum_names.h"

namespace laser_raycast {

// A double the way it is written back to parse to the same value ("0.1", "3.141592653589793").
std::string formatNumber(double value);
// A parameter value as YAML would write it ('text', 0.5, true, [a, b], {k: v}), for messages.
std::string describeValue(const XmlRpc::XmlRpcValue& value);
// The first n names, comma-separated, then "... (N more)" if there are more.
std::string joinFirst(const std::vector<std::string>& names, std::size_t n);
// "bool", "int", "double", "string", "list", "dict".
const char* typeName(XmlRpc::XmlRpcValue::Type type);

class ParamReader {
 public:
  // values: a struct of parameters, or an invalid value for "none set" (anything else is an
  // error). prefix names the namespace in messages and log lines: "~" for the private one.
  ParamReader(const XmlRpc::XmlRpcValue& values, std::string prefix);

  // Whether the parameter is set. Every accessor marks the name as known.
  bool has(const std::string& name);
  // The value, or nullptr if unset.
  const XmlRpc::XmlRpcValue* get(const std::string& name);
  // The value of a list or dict parameter, or nullptr if unset. roscpp sets _name:=[a, b] from the
  // command line as a string: a string holding a YAML list or dict is read as that list or dict
  // (parseYamlContainer), so that the caller's checks apply to it; one that is not YAML, or holds
  // what no parameter can (a null), fails naming the parameter and the string (then nullptr); any
  // other string is returned as it is, for the caller to refuse as not `expected`.
  const XmlRpc::XmlRpcValue* container(const std::string& name, const char* expected);

  // Scalars: the fallback if unset, logged as "<prefix>name = value unit". A number may be given
  // as an int or a double.
  double number(const std::string& name, double fallback, const char* unit);
  int integer(const std::string& name, int fallback, const char* unit);
  bool boolean(const std::string& name, bool fallback);
  std::string text(const std::string& name, const std::string& fallback);
  std::vector<std::string> textList(const std::string& name);
  // A list of numbers (ints or doubles), the fallback if unset; logged as "[a, b] unit".
  std::vector<double> numberList(const std::string& name, const std::vector<double>& fallback,
                                 const char* unit);
  // A string naming one entry of a table (fallback if unset; an error naming the choices if not in
  // it).
  template <typename E, std::size_t N>
  E choice(const std::string& name, E fallback, const core::EnumNames<E, N>& table) {
    const std::string given = text(name, table.name(fallback));
    E value = fallback;
    if (!table.parse(given, &value)) fail(name, table.notOneOf(given));
    return value;
  }

  // A line for the start-up log.
  void note(const std::string& line) { log_.push_back(line); }
  // "parameter <prefix>name: message" (the first error wins).
  void fail(const std::string& name, const std::string& message);
  // A message that already names the parameter.
  void failWith(const std::string& message);
  // "parameter <prefix>name: is a string ('fast'), expected a number".
  void wrongType(const std::string& name, const XmlRpc::XmlRpcValue& value, const char* expected);

  const std::string& prefix() const { return prefix_; }
  const std::string& error() const { return error_; }
  const std::vector<std::string>& log() const { return log_; }
  // Every name asked for so far, in the order first asked.
  const std::vector<std::string>& known() const { return known_order_; }
  // Keys of the struct that no accessor asked for.
  std::vector<std::string> unknown() const;

 private:
  // The fallback if unset; otherwise the converted value, or the fallback after a type error.
  template <typename T, class Convert>
  T scalar(const std::string& name, const T& fallback, const char* expected, Convert convert) {
    const XmlRpc::XmlRpcValue* v = get(name);
    T value = fallback;
    if (v && !convert(*v, &value)) wrongType(name, *v, expected);
    return value;
  }

  const XmlRpc::XmlRpcValue& values_;
  // The lists and dicts read from strings, by name (a map: the values stay where they are).
  std::map<std::string, XmlRpc::XmlRpcValue> from_yaml_;
  std::string prefix_;
  std::set<std::string> known_;
  std::vector<std::string> known_order_;
  std::vector<std::string> log_;
  std::string error_;
};

}  // namespace laser_raycast
