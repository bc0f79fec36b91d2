// The node's parameters that hold entries (the models and map lists, the reflectivity dict) and
// the lists and dicts given as strings of YAML, as roscpp sets them from the command line: each
// value reaching its field, and each bad entry refused with a message that names the parameter,
// the entry and the value. Parsed from values built here (no parameter server, no roscore).
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

#include "laser_raycast/node/node_params.h"
#include "node_params_inputs.h"

namespace laser_raycast_test {
namespace {

using XmlRpc::XmlRpcValue;

TEST(NodeParams, BadModelsEntriesNameTheEntry) {
  const auto models = [](const XmlRpcValue& entry) {
    return values({{"models", list({values({{"param", "robot_description"}}), entry})}});
  };
  expectRefused(models(values({{"param", "a"}, {"file", "/b.urdf"}})),
                {"~models[1]", "exactly one of 'param', 'file', 'map' and 'map_topic'", "/b.urdf"});
  expectRefused(models(values({{"tf_prefix", "r2/"}})), {"~models[1]", "exactly one of"});
  expectRefused(models(values({{"param", ""}})), {"~models[1]", "exactly one of"});
  expectRefused(models(values({{"path", "/b.urdf"}})), {"~models[1]", "unknown key 'path'"});
  expectRefused(models(values({{"param", 5}})), {"~models[1]/param", "int (5)", "a string"});
  expectRefused(models(XmlRpcValue(3)), {"~models[1]", "int (3)", "a parameter name or a dict"});
  expectRefused(models(values({{"file", "/b.urdf"}, {"tf_prefix", "/r2/"}})),
                {"~models[1]", "tf_prefix '/r2/'", "'/'"});
}

TEST(NodeParams, MapEntries) {
  const Parsed parsed = parse(values(
      {{"models",
        list({values(
                  {{"map", "package://pkg/maps/office.yaml"}, {"height", 1.5}, {"frame", "world"}}),
              values({{"map", "/maps/lab.yaml"}}),
              values({{"map_topic", "/map"}, {"height", 3}})})}}));
  ASSERT_EQ(parsed.error, "");
  const auto& m = parsed.params.models;
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].map, "package://pkg/maps/office.yaml");
  EXPECT_EQ(m[0].height, 1.5);
  EXPECT_EQ(m[0].frame, "world");
  EXPECT_EQ(m[0].param, "");
  EXPECT_EQ(m[1].map, "/maps/lab.yaml");
  EXPECT_EQ(m[1].height, laser_raycast::MapWallOptions::kDefaultHeight);
  EXPECT_EQ(m[1].frame, "map");
  EXPECT_EQ(m[2].map_topic, "/map");
  EXPECT_EQ(m[2].height, 3.0);
  EXPECT_TRUE(m[2].isMap());
  const auto logged = [&](const std::string& line) {
    const auto& v = parsed.report.values;
    EXPECT_NE(std::find(v.begin(), v.end(), line), v.end()) << line;
  };
  logged("~models[0] = map package://pkg/maps/office.yaml, walls 1.5 m high in frame 'world'");
  logged("~models[2] = map topic /map, walls 3 m high");
}

TEST(NodeParams, BadMapEntriesNameTheEntry) {
  const auto models = [](const XmlRpcValue& entry) {
    return values({{"models", list({values({{"param", "robot_description"}}), entry})}});
  };
  expectRefused(models(values({{"map", "/m.yaml"}, {"height", 0}})),
                {"~models[1]/height", "> 0", "got 0"});
  expectRefused(models(values({{"map", "/m.yaml"}, {"height", -2.5}})),
                {"~models[1]/height", "got -2.5"});
  expectRefused(models(values({{"map", "/m.yaml"}, {"height", "tall"}})),
                {"~models[1]/height", "string ('tall')", "a number"});
  expectRefused(models(values({{"map", "/m.yaml"}, {"heigth", 2}})),
                {"~models[1]", "unknown key 'heigth'", "height"});
  expectRefused(models(values({{"map", "/m.yaml"}, {"file", "/b.urdf"}})),
                {"~models[1]", "exactly one of"});
  expectRefused(models(values({{"map", "/m.yaml"}, {"tf_prefix", "r2/"}})),
                {"~models[1]", "'tf_prefix' does not go with 'map'"});
  expectRefused(models(values({{"file", "/b.urdf"}, {"height", 2}})),
                {"~models[1]", "'height' does not go with 'file'"});
  // A map topic's walls are not a model of their own (~list_models): no name.
  expectRefused(models(values({{"map_topic", "/map"}, {"name", "walls"}})),
                {"~models[1]", "'name' does not go with 'map_topic'"});
  expectRefused(models(values({{"map_topic", "/map"}, {"frame", "odom"}})),
                {"~models[1]", "'frame' does not go with 'map_topic'", "the grid gives the frame"});
  expectRefused(models(values({{"map", "/m.yaml"}, {"frame", "/map"}})),
                {"~models[1]/frame", "'/map'", "'/'"});
  expectRefused(models(values({{"map", "/m.yaml"}, {"frame", ""}})),
                {"~models[1]/frame", "must not be empty"});
  expectRefused(models(values({{"map_topic", "bad topic"}})),
                {"~models[1]/map_topic", "'bad topic'", "not a valid topic name"});
}

TEST(NodeParams, ReflectivityOfLinksWithATfPrefix) {
  // The parameter server stores {r2/wall: 0.5} as the nested dict {r2: {wall: 0.5}}.
  const Parsed parsed =
      parse(values({{"intensity", "reflectivity"},
                    {"reflectivity", values({{"r2", values({{"wall", 0.5}})}, {"floor", 0}})}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_EQ(parsed.params.reflectivity,
            (std::map<std::string, double>{{"r2/wall", 0.5}, {"floor", 0.0}}));
  expectRefused(values({{"reflectivity", values({{"r2", values({{"wall", -2}})}})}}),
                {"~reflectivity/r2/wall", "got -2"});
  expectRefused(values({{"reflectivity", values({{"r2", values({{"wall", "x"}})}})}}),
                {"~reflectivity/r2/wall", "'x'", "a number"});
}

// roscpp sets _elevations:="[-0.1, 0.1]" from the command line as a string: every list and dict
// parameter given as a string of YAML is read as that list or dict, with the same values, log lines
// and checks as when the parameter server holds one (the nested reflectivity dict the server makes
// of a "r2/wall" key included).
TEST(NodeParams, ListsAndDictsGivenAsYamlStrings) {
  const XmlRpcValue as_values =
      values({{"elevations", list({-0.1, 0.1})},
              {"models", list({values({{"param", "scene"}, {"tf_prefix", "s/"}}), "other"})},
              {"ignore_links", list({"s/arm", "slider"})},
              {"intensity", "reflectivity"},
              {"reflectivity", values({{"wall", 0.5}, {"r2", values({{"wall", 2}})}})},
              {"sensors", list({values({{"frame_id", "front"}, {"elevations", list({0})}}),
                                values({{"frame_id", "top"}, {"sensor_model", "VLP-16"}})})}});
  const XmlRpcValue as_strings = values(
      {{"elevations", "[-0.1, 0.1]"},
       {"models", "[{param: scene, tf_prefix: s/}, other]"},
       {"ignore_links", "[s/arm, slider]"},
       {"intensity", "reflectivity"},
       {"reflectivity", "{wall: 0.5, r2/wall: 2}"},
       {"sensors", "[{frame_id: front, elevations: [0]}, {frame_id: top, sensor_model: VLP-16}]"}});
  const Parsed expected = parse(as_values), got = parse(as_strings);
  ASSERT_EQ(expected.error, "");
  ASSERT_EQ(got.error, "");
  EXPECT_EQ(got.report.values, expected.report.values);  // every value, as logged
  EXPECT_EQ(got.report.warnings, expected.report.warnings);
  EXPECT_EQ(got.params.sensors.at(1).scan.elevations.size(), 16u);
  EXPECT_EQ(got.params.reflectivity,
            (std::map<std::string, double>{{"wall", 0.5}, {"r2/wall", 2}}));
  // A string inside an entry of ~sensors too.
  const Parsed entry = parse(
      values({{"sensors", list({values({{"frame_id", "a"}, {"elevations", "[0.2, -0.2]"}})})}}));
  ASSERT_EQ(entry.error, "");
  EXPECT_EQ(entry.params.sensors.at(0).scan.elevations, (std::vector<double>{0.2, -0.2}));
}

// The checks are those of a list or dict, naming the parameter; a string that is not YAML, or
// holds a null, is refused naming the parameter and the string; a string that YAML reads as a
// scalar is refused as a string.
TEST(NodeParams, YamlStringsAreCheckedAsTheirValues) {
  expectRefused(values({{"elevations", "[-0.1, 0.1"}}),
                {"~elevations", "'[-0.1, 0.1'", "YAML", "line 1", "a list of numbers"});
  expectRefused(values({{"elevations", "[0.1, up]"}}), {"~elevations[1]", "'up'", "a number"});
  expectRefused(values({{"elevations", "[]"}}), {"~elevations", "must not be empty"});
  expectRefused(values({{"elevations", "{a: 1}"}}), {"~elevations", "is a dict ({a: 1})"});
  expectRefused(values({{"ignore_links", "base"}}),
                {"~ignore_links", "is a string ('base')", "a list of strings"});
  expectRefused(values({{"ignore_links", "[a, ~]"}}), {"~ignore_links", "'[a, ~]'", "[1] is null"});
  expectRefused(values({{"models", "[{param: a, file: b}]"}}), {"~models[0]", "exactly one"});
  expectRefused(values({{"reflectivity", "{wall: -1}"}}), {"~reflectivity/wall", "got -1"});
  expectRefused(values({{"reflectivity", "[wall]"}}), {"~reflectivity", "is a list", "a dict"});
  expectRefused(values({{"sensors", "[{samples: 10}]"}}), {"~sensors[0]/frame_id", "not set"});
  expectRefused(values({{"sensors", "[{frame_id: }]"}}), {"~sensors", "[0]/frame_id is null"});
}

}  // namespace
}  // namespace laser_raycast_test
