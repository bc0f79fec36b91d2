// parseYamlContainer: a string of YAML read as the list or dict the parameter server would hold
// (roscpp sets _name:=[a, b] from the command line as a string), scalars typed by YAML 1.2's core
// schema; what is not a list or dict left alone, and what is not YAML or holds what no parameter
// can refused naming where.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "node_params_inputs.h"
#include "yaml_value.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::parseYamlContainer;
using XmlRpc::XmlRpcValue;

XmlRpcValue parsed(const std::string& text) {
  XmlRpcValue value;
  std::string error;
  EXPECT_TRUE(parseYamlContainer(text, &value, &error)) << text << ": " << error;
  EXPECT_EQ(error, "");
  return value;
}

// Refused, with every one of `mentions` in the message.
void expectRefusedYaml(const std::string& text, const std::vector<std::string>& mentions) {
  XmlRpcValue value;
  std::string error;
  EXPECT_FALSE(parseYamlContainer(text, &value, &error)) << text;
  EXPECT_FALSE(error.empty()) << text;
  expectMentions(error, mentions);
}

TEST(YamlValue, ListsOfNumbers) {
  EXPECT_EQ(parsed("[-0.1, 0.1]"), list({-0.1, 0.1}));
  // Integers stay ints (the parser takes ints for numbers); exponents, +, leading points.
  const XmlRpcValue v = parsed("[0, -3, +2, 1e-3, 2.5E+2, .5, -7.]");
  EXPECT_EQ(v, list({0, -3, 2, 1e-3, 250.0, 0.5, -7.0}));
  EXPECT_EQ(v[0].getType(), XmlRpcValue::TypeInt);
  EXPECT_EQ(v[3].getType(), XmlRpcValue::TypeDouble);
  // Block style too.
  EXPECT_EQ(parsed("- 0.25\n- -0.25\n"), list({0.25, -0.25}));
  const XmlRpcValue special = parsed("[.inf, -.Inf, +.INF, .nan]");
  EXPECT_EQ(static_cast<double>(special[0]), std::numeric_limits<double>::infinity());
  EXPECT_EQ(static_cast<double>(special[1]), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(static_cast<double>(special[2]), std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(static_cast<double>(special[3])));
  EXPECT_EQ(parsed("[]"), list({}));
}

// Plain words are strings, also ones YAML 1.1 took for bools (yes, on); quoted or !!str scalars
// are strings whatever they look like; true and false in their three spellings are bools.
TEST(YamlValue, StringsAndBools) {
  EXPECT_EQ(parsed("[base_scan, s/arm, yes, on, 1.2.3]"),
            list({"base_scan", "s/arm", "yes", "on", "1.2.3"}));
  EXPECT_EQ(parsed("['0.5', \"7\", !!str 8]"), list({"0.5", "7", "8"}));
  EXPECT_EQ(parsed("[true, True, TRUE, false, False, FALSE]"),
            list({true, true, true, false, false, false}));
}

// Dicts become structs, keys as written ('/' included: the node joins the parameter server's
// nested names to the same), also inside lists, as ~sensors and ~models hold them.
TEST(YamlValue, DictsAndNesting) {
  EXPECT_EQ(parsed("{wall: 0.5, r2/wall: 2}"), values({{"wall", 0.5}, {"r2/wall", 2}}));
  EXPECT_EQ(parsed("{}"), values({}));
  EXPECT_EQ(parsed("[{frame_id: front, samples: 100}, {frame_id: top, elevations: [0.1, -0.1]}]"),
            list({values({{"frame_id", "front"}, {"samples", 100}}),
                  values({{"frame_id", "top"}, {"elevations", list({0.1, -0.1})}})}));
  EXPECT_EQ(parsed("[{param: robot_description}, {file: /a/b.urdf, tf_prefix: t/}]"),
            list({values({{"param", "robot_description"}}),
                  values({{"file", "/a/b.urdf"}, {"tf_prefix", "t/"}})}));
  EXPECT_EQ(parsed("sensors:\n  - {frame_id: a}\n"),
            values({{"sensors", list({values({{"frame_id", "a"}})})}}));
}

// A scalar, or nothing, is not a list or dict: false, no error, the value untouched.
TEST(YamlValue, ScalarsAreLeftToTheCaller) {
  for (const std::string text : {"robot_description", "0.5", "", "'[0.1]'", "true"}) {
    XmlRpcValue value = 3;
    std::string error = "stale";
    EXPECT_FALSE(parseYamlContainer(text, &value, &error)) << text;
    EXPECT_EQ(error, "") << text;
    EXPECT_EQ(value, XmlRpcValue(3)) << text;
  }
}

TEST(YamlValue, NotYamlOrNotAParameterIsRefusedSayingWhere) {
  expectRefusedYaml("[-0.1, 0.1", {"line 1, column 1", "end of sequence"});
  expectRefusedYaml("[a, b]]", {"line 1, column 7"});
  expectRefusedYaml("{a: [1, 2}", {"line 1"});
  // The parameter server has no null, and 32-bit ints.
  expectRefusedYaml("[0.1, ~]", {"[1] is null"});
  expectRefusedYaml("[0.1, null]", {"[1] is null"});
  expectRefusedYaml("{wall: }", {"wall is null"});
  expectRefusedYaml("[{frame_id: a}, {frame_id: }]", {"[1]/frame_id is null"});
  expectRefusedYaml("[3000000000]", {"[0] is the integer 3000000000", "int32"});
  expectRefusedYaml("[-99999999999999999999]", {"[0] is the integer", "int32"});
  expectRefusedYaml("{[x]: 2}", {"a key is not a scalar"});
  XmlRpcValue untouched = 3;
  std::string error;
  EXPECT_FALSE(parseYamlContainer("[1, ~]", &untouched, &error));
  EXPECT_EQ(untouched, XmlRpcValue(3));
}

}  // namespace
}  // namespace laser_raycast_test
