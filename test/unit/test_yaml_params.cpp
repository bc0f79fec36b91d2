// simulate_bag's configuration: YAML read into parameters as `rosparam load` sets them. The types
// and values of the scalars are compared with what rosparam itself (Debian's python3-rosparam,
// which the node's launch files use) makes of the same file; nesting, and what the parameter server
// cannot hold, by hand. The repository's configurations parse as the node parses its parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>
#include <string>

#include "laser_raycast/node/node_params.h"
#include "run_command.h"
#include "temp_files.h"
#include "yaml_params.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::loadYamlParams;
using laser_raycast::parseYamlParams;
using laser_raycast::YamlParamsError;
using Type = XmlRpc::XmlRpcValue::Type;

const std::string kSource = LASER_RAYCAST_SOURCE_DIR;

// Scalars in each of the forms YAML 1.1 resolves: booleans, integers in every base and base 60,
// floats (a signed exponent only), and what stays a string.
const char* const kScalars = R"(b1: yes
b2: Off
b3: TRUE
b4: on
b5: NO
i1: 0x1F
i2: 017
i3: 1_000
i4: 0b101
i5: 1:30
i6: -42
i7: +7
i8: 0
i9: -2147483648
f1: 1.5
f2: 1.0e+3
f3: .inf
f4: -.Inf
f5: .NaN
f6: 1:30.5
f7: .5
f8: 3.
f9: !!float 2
f10: -1_000.25
s1: 1e5
s2: '12'
s3: !!str 7
s4: y
s5: hello
s6: 1.0e5
s7: "true"
s8: 0o17
s9: 1.2.3
s10: ~foo
s11: rad(pi)
)";

// What rosparam loads from a file: per key, its Python type and repr.
std::map<std::string, std::pair<std::string, std::string>> rosparamLoad(const std::string& path) {
  const CommandResult r = runCommand(
      "/usr/bin/python3 -c \"import sys, rosparam\n"
      "for params, ns in rosparam.load_file(sys.argv[1]):\n"
      "    for k in sorted(params): print(k, type(params[k]).__name__, repr(params[k]))\" " +
      path + " 2>&1");
  EXPECT_EQ(r.status, 0) << r.output;
  std::map<std::string, std::pair<std::string, std::string>> out;
  std::istringstream lines(r.output);
  std::string key, type, value;
  while (lines >> key >> type && std::getline(lines >> std::ws, value)) out[key] = {type, value};
  return out;
}

TEST(YamlParams, ScalarsTakeTheTypesAndValuesRosparamGivesThem) {
  const std::string path = writeFile("scalars.yaml", kScalars);
  const auto expected = rosparamLoad(path);
  ASSERT_EQ(expected.size(), 35u);
  XmlRpc::XmlRpcValue params = loadYamlParams(path);
  ASSERT_EQ(params.size(), 35);
  for (const auto& [key, python] : expected) {
    SCOPED_TRACE(key + ": rosparam gives " + python.first + " " + python.second);
    ASSERT_TRUE(params.hasMember(key));
    XmlRpc::XmlRpcValue& v = params[key];
    const std::string& text = python.second;
    if (key == "s11") {
      // rosparam evaluates its own rad() and deg() forms; the parameters take them as text, which
      // the node refuses for a number with a message naming the value.
      EXPECT_EQ(python.first, "float");
      EXPECT_EQ(v.getType(), Type::TypeString);
    } else if (python.first == "bool") {
      ASSERT_EQ(v.getType(), Type::TypeBoolean);
      EXPECT_EQ(static_cast<bool>(v), text == "True");
    } else if (python.first == "int") {
      ASSERT_EQ(v.getType(), Type::TypeInt);
      EXPECT_EQ(static_cast<int>(v), std::stoi(text));
    } else if (python.first == "float") {
      ASSERT_EQ(v.getType(), Type::TypeDouble);
      const double value = std::strtod(text.c_str(), nullptr);
      if (std::isnan(value)) {
        EXPECT_TRUE(std::isnan(static_cast<double>(v)));
      } else {
        EXPECT_EQ(static_cast<double>(v), value);
      }
    } else {
      ASSERT_EQ(python.first, "str");
      ASSERT_EQ(v.getType(), Type::TypeString);
      EXPECT_EQ("'" + static_cast<std::string>(v) + "'", text);
    }
  }
}

TEST(YamlParams, MappingsAreStructsAndSequencesArrays) {
  XmlRpc::XmlRpcValue p =
      parseYamlParams("nested: {a: [1, 2.5, x], b: {c: no}, e: {}}\nlist: []\n", "nested.yaml");
  XmlRpc::XmlRpcValue& nested = p["nested"];
  ASSERT_EQ(nested.getType(), Type::TypeStruct);
  ASSERT_EQ(nested["a"].getType(), Type::TypeArray);
  ASSERT_EQ(nested["a"].size(), 3);
  EXPECT_EQ(static_cast<int>(nested["a"][0]), 1);
  EXPECT_EQ(static_cast<double>(nested["a"][1]), 2.5);
  EXPECT_EQ(static_cast<std::string>(nested["a"][2]), "x");
  EXPECT_EQ(static_cast<bool>(nested["b"]["c"]), false);
  EXPECT_EQ(nested["e"].getType(), Type::TypeStruct);
  EXPECT_EQ(nested["e"].size(), 0);
  EXPECT_EQ(p["list"].getType(), Type::TypeArray);
  EXPECT_EQ(p["list"].size(), 0);
}

// The message of the error parsing `text` throws.
std::string errorOf(const std::string& text) {
  try {
    parseYamlParams(text, "bad.yaml");
  } catch (const YamlParamsError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return "";
}

TEST(YamlParams, WhatTheParameterServerCannotHoldIsRefusedWithItsPlace) {
  EXPECT_EQ(errorOf("a: 1\nsensors:\n  - {rate: }\n"),
            "bad.yaml:3:12: sensors[0]/rate: has no value (null), which the parameter server "
            "cannot hold");
  EXPECT_EQ(errorOf("a: 2147483648\n"),
            "bad.yaml:1:4: a: 2147483648 is beyond the 32-bit integers the parameter server "
            "holds");
  EXPECT_EQ(errorOf("a: !!int 1.5\n"), "bad.yaml:1:4: a: '1.5' is not an integer");
  EXPECT_EQ(errorOf("a: !mine 1\n"),
            "bad.yaml:1:4: a: the tag !mine is not one the parameter server takes");
  EXPECT_EQ(errorOf("[1, 2]\n"),
            "bad.yaml: the top level must be a mapping of parameter names to values");
  EXPECT_EQ(errorOf(""), "bad.yaml: the top level must be a mapping of parameter names to values");
  EXPECT_NE(errorOf("a: [1,\nb: 2\n").find("bad.yaml:3:1: not YAML: "), std::string::npos);
  EXPECT_NE(errorOf("? [1, 2]\n: 3\n").find("a key that is not a scalar"), std::string::npos);
  try {
    loadYamlParams(kSource + "/test/data");
    ADD_FAILURE() << "a directory was read";
  } catch (const YamlParamsError& e) {
    EXPECT_EQ(std::string(e.what()), kSource + "/test/data: is a directory, not a YAML file");
  }
}

// A configuration file of the repository parses as the node parses its parameters.
void expectNodeParameters(const std::string& file, std::size_t sensors) {
  laser_raycast::NodeParams params;
  laser_raycast::ParamReport report;
  const std::string error =
      parseNodeParams(loadYamlParams(kSource + "/" + file), "/", &params, &report);
  EXPECT_EQ(error, "") << file;
  EXPECT_TRUE(report.warnings.empty()) << file << ": " << report.warnings.front();
  EXPECT_EQ(params.sensors.size(), sensors) << file;
  for (const laser_raycast::ModelSource& model : params.models) {
    EXPECT_NE(model.file, "") << file << ": models are files for simulate_bag";
  }
}

TEST(YamlParams, TheRepositorysConfigurationsAreTheNodesParameters) {
  expectNodeParameters("config/simulate_bag_example.yaml", 2);
  expectNodeParameters("test/data/simulate_bag_test.yaml", 4);
}

}  // namespace
}  // namespace laser_raycast_test
