// The node's parameters, parsed from values built here (no parameter server, no roscore): every
// default, each value reaching its field, and each wrong type, range and combination refused with a
// message that names the parameter and the value.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/node/node_params.h"
#include "node_params_inputs.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::NodeParams;
using XmlRpc::XmlRpcValue;

const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

// One parameter set to a bad value, and what the message must say.
struct BadValue {
  const char* name;
  XmlRpcValue value;
  std::vector<std::string> mentions;
};

void expectEachRefused(const std::vector<BadValue>& cases) {
  for (const BadValue& c : cases) {
    SCOPED_TRACE(c.name);
    expectRefused(values({{c.name, c.value}}), c.mentions);
  }
}

// The parameters as the README's table lists them.
const std::vector<std::string> kReadmeParameters = {"frame_id",
                                                    "fixed_frame",
                                                    "angle_min",
                                                    "angle_max",
                                                    "angle_increment",
                                                    "samples",
                                                    "range_min",
                                                    "range_max",
                                                    "min_range_policy",
                                                    "rate",
                                                    "tf_timeout",
                                                    "threads",
                                                    "models",
                                                    "geometry",
                                                    "ignore_links",
                                                    "skip_bad_geometry",
                                                    "mesh_import_max_memory_mb",
                                                    "mesh_import_timeout",
                                                    "noise_stddev",
                                                    "noise_seed",
                                                    "intensity",
                                                    "reflectivity",
                                                    "default_reflectivity",
                                                    "method",
                                                    "cull_backfaces",
                                                    "pose_topic",
                                                    "pose_frame",
                                                    "pose_timeout",
                                                    "sensor_model",
                                                    "elevations",
                                                    "sweep",
                                                    "scan_time",
                                                    "organized",
                                                    "point_layout",
                                                    "range_bias",
                                                    "range_resolution",
                                                    "dropout_probability",
                                                    "surface_reflectance",
                                                    "reflectance_from_color",
                                                    "detection_range",
                                                    "detection_reflectivity",
                                                    "beam_divergence",
                                                    "beam_samples",
                                                    "return_mode",
                                                    "min_return_separation",
                                                    "pattern_file",
                                                    "points_per_scan",
                                                    "point_rate",
                                                    "calibration_file",
                                                    "ouster_metadata",
                                                    "sensors"};

TEST(NodeParams, TheNodeReadsExactlyTheDocumentedParameters) {
  std::vector<std::string> read = laser_raycast::nodeParamNames();
  std::vector<std::string> documented = kReadmeParameters;
  std::sort(read.begin(), read.end());
  std::sort(documented.begin(), documented.end());
  EXPECT_EQ(read, documented);
}

TEST(NodeParams, EveryDefault) {
  // Nothing set at all (the namespace does not exist) and an empty namespace mean the same.
  for (const XmlRpcValue& v : {XmlRpcValue(), values({})}) {
    const Parsed parsed = parse(v);
    ASSERT_EQ(parsed.error, "");
    EXPECT_TRUE(parsed.report.warnings.empty()) << parsed.report.warnings.front();
    const NodeParams& p = parsed.params;
    EXPECT_EQ(p.sensors.at(0).frame_id, "laser");
    EXPECT_EQ(p.fixed_frame, "map");
    EXPECT_EQ(p.sensors.at(0).scan.fan.angle_min, -M_PI);
    EXPECT_EQ(p.sensors.at(0).scan.fan.angle_max, M_PI);
    EXPECT_EQ(p.sensors.at(0).scan.fan.angle_increment, 0.0);  // unset: from samples
    EXPECT_EQ(p.sensors.at(0).scan.fan.samples, 360);
    EXPECT_EQ(p.sensors.at(0).scan.output.range_min, 0.0);
    EXPECT_EQ(p.sensors.at(0).scan.output.range_max, 30.0);
    EXPECT_EQ(p.sensors.at(0).scan.output.min_range_policy,
              laser_raycast::core::MinRangePolicy::kNegInf);
    EXPECT_EQ(p.sensors.at(0).scan.output.noise_stddev, 0.0);
    EXPECT_EQ(p.sensors.at(0).scan.output.noise_seed, 0u);
    EXPECT_FALSE(p.sensors.at(0).scan.output.intensity);
    EXPECT_EQ(p.sensors.at(0).scan.method, laser_raycast::core::TriangleMethod::kWatertight);
    EXPECT_FALSE(p.sensors.at(0).scan.cull_backfaces);
    EXPECT_EQ(p.sensors.at(0).scan.elevations, std::vector<double>{0.0});
    EXPECT_EQ(p.sensors.at(0).rate, 10.0);
    EXPECT_EQ(p.tf_timeout, 0.5);
    EXPECT_EQ(p.threads, 1);
    EXPECT_EQ(p.sensors.at(0).pose_timeout, 0.5);
    ASSERT_EQ(p.sensors.size(), 1u);
    const laser_raycast::SensorParams& s = p.sensors[0];
    EXPECT_EQ(s.name, "laser");  // the shorthand's: its frame
    EXPECT_EQ(s.topic, "scan");
    EXPECT_EQ(s.sensor_model, "");
    EXPECT_EQ(s.sweep, laser_raycast::Sweep::kInstant);
    EXPECT_EQ(s.scan_time, 0.0);
    EXPECT_EQ(s.scanTime(), 0.1);
    EXPECT_EQ(s.timeIncrement(), 0.0);
    EXPECT_FALSE(s.organized);
    EXPECT_EQ(s.point_layout, laser_raycast::PointLayout::kVelodyne);
    EXPECT_EQ(s.scan.output.range_bias, 0.0);
    EXPECT_EQ(s.scan.output.range_resolution, 0.0);
    EXPECT_EQ(s.scan.output.dropout_probability, 0.0);
    EXPECT_EQ(p.geometry, laser_raycast::GeometrySource::kVisual);
    EXPECT_FALSE(p.skip_bad_geometry);
    EXPECT_EQ(p.mesh_import.max_memory_mb, 0.0);  // by the file's size
    EXPECT_EQ(p.mesh_import.max_seconds, 0.0);
    ASSERT_EQ(p.models.size(), 1u);
    EXPECT_EQ(p.models[0].param, "robot_description");
    EXPECT_EQ(p.models[0].file, "");
    EXPECT_EQ(p.models[0].tf_prefix, "");
    EXPECT_TRUE(p.ignore_links.empty());
    EXPECT_TRUE(p.reflectivity.empty());
    EXPECT_EQ(p.default_reflectivity, 1.0);
    EXPECT_EQ(p.sensors.at(0).pose_topic, "");
    EXPECT_EQ(p.sensors.at(0).pose_frame, "");
  }
}

TEST(NodeParams, EveryParameterIsLoggedOnceWithItsExactValue) {
  const Parsed parsed = parse(values({}));
  for (const std::string& name : kReadmeParameters) {
    int lines = 0;
    for (const std::string& line : parsed.report.values) {
      const std::string head = "~" + name;
      if (line.compare(0, head.size(), head) == 0 &&
          (line.size() == head.size() || line[head.size()] == ' ' || line[head.size()] == '[')) {
        ++lines;
      }
    }
    EXPECT_EQ(lines, 1) << name;
  }
  const auto& log = parsed.report.values;
  for (const char* line :
       {"~angle_min = -3.141592653589793 rad", "~tf_timeout = 0.5 s", "~pose_timeout = 0.5 s",
        "~rate = 10 Hz", "~frame_id = 'laser'", "~samples = 360 beams",
        "~min_range_policy = '-inf'", "~models[0] = parameter robot_description",
        "~reflectivity = {}", "~ignore_links = []", "~cull_backfaces = false"}) {
    EXPECT_NE(std::find(log.begin(), log.end(), line), log.end()) << line;
  }
}

TEST(NodeParams, EveryValueReachesItsField) {
  XmlRpcValue models =
      list({values({{"param", "robot_description"}}),
            values({{"file", "package://pkg/world.urdf"}, {"tf_prefix", "w/"}, {"name", "world"}}),
            XmlRpcValue("other_description")});
  const Parsed parsed = parse(values({{"frame_id", "base_scan"},
                                      {"fixed_frame", "odom"},
                                      {"angle_min", -1.5},
                                      {"angle_max", 2},  // an int is a number too
                                      {"samples", 100},
                                      {"range_min", 0.12},
                                      {"range_max", 3.5},
                                      {"min_range_policy", "pass_through"},
                                      {"rate", 5.5},
                                      {"tf_timeout", 0},
                                      {"threads", 2},
                                      {"models", models},
                                      {"geometry", "collision"},
                                      {"ignore_links", list({"base_scan", "w/wall"})},
                                      {"skip_bad_geometry", true},
                                      {"mesh_import_max_memory_mb", 4096},
                                      {"mesh_import_timeout", 120.5},
                                      {"noise_stddev", 0.01},
                                      {"noise_seed", 42},
                                      {"intensity", "reflectivity"},
                                      {"reflectivity", values({{"a", 0.5}, {"b", 2}})},
                                      {"default_reflectivity", 0.25},
                                      {"method", "moller_trumbore"},
                                      {"cull_backfaces", true},
                                      {"pose_topic", "/pose"},
                                      {"pose_frame", "base_link"},
                                      {"pose_timeout", 0.25}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_TRUE(parsed.report.warnings.empty()) << parsed.report.warnings.front();
  const NodeParams& p = parsed.params;
  EXPECT_EQ(p.sensors.at(0).frame_id, "base_scan");
  EXPECT_EQ(p.fixed_frame, "odom");
  EXPECT_EQ(p.sensors.at(0).scan.fan.angle_min, -1.5);
  EXPECT_EQ(p.sensors.at(0).scan.fan.angle_max, 2.0);
  EXPECT_EQ(p.sensors.at(0).scan.fan.samples, 100);
  EXPECT_EQ(p.sensors.at(0).scan.fan.angle_increment, 0.0);
  EXPECT_EQ(p.sensors.at(0).scan.output.range_min, 0.12);
  EXPECT_EQ(p.sensors.at(0).scan.output.range_max, 3.5);
  EXPECT_EQ(p.sensors.at(0).scan.output.min_range_policy,
            laser_raycast::core::MinRangePolicy::kPassThrough);
  EXPECT_EQ(p.sensors.at(0).rate, 5.5);
  EXPECT_EQ(p.tf_timeout, 0.0);
  EXPECT_EQ(p.threads, 2);
  ASSERT_EQ(p.models.size(), 3u);
  EXPECT_EQ(p.models[0].param, "robot_description");
  EXPECT_EQ(p.models[1].file, "package://pkg/world.urdf");
  EXPECT_EQ(p.models[1].param, "");
  EXPECT_EQ(p.models[1].tf_prefix, "w/");
  EXPECT_EQ(p.models[1].name, "world");
  EXPECT_EQ(p.models[0].name, "");  // the URDF's robot name, when loaded
  EXPECT_EQ(p.models[2].param, "other_description");
  EXPECT_EQ(p.geometry, laser_raycast::GeometrySource::kCollision);
  EXPECT_EQ(p.ignore_links, (std::vector<std::string>{"base_scan", "w/wall"}));
  EXPECT_TRUE(p.skip_bad_geometry);
  EXPECT_EQ(p.mesh_import.max_memory_mb, 4096.0);
  EXPECT_EQ(p.mesh_import.max_seconds, 120.5);
  EXPECT_EQ(p.sensors.at(0).scan.output.noise_stddev, 0.01);
  EXPECT_EQ(p.sensors.at(0).scan.output.noise_seed, 42u);
  EXPECT_TRUE(p.sensors.at(0).scan.output.intensity);
  EXPECT_EQ(p.reflectivity, (std::map<std::string, double>{{"a", 0.5}, {"b", 2.0}}));
  EXPECT_EQ(p.default_reflectivity, 0.25);
  EXPECT_EQ(p.sensors.at(0).scan.method, laser_raycast::core::TriangleMethod::kMollerTrumbore);
  EXPECT_TRUE(p.sensors.at(0).scan.cull_backfaces);
  EXPECT_EQ(p.sensors.at(0).pose_topic, "/pose");
  EXPECT_EQ(p.sensors.at(0).pose_frame, "base_link");
  EXPECT_EQ(p.sensors.at(0).pose_timeout, 0.25);
}

TEST(NodeParams, AngleIncrementInsteadOfSamples) {
  const Parsed parsed =
      parse(values({{"angle_min", -1.0}, {"angle_max", 1.0}, {"angle_increment", 0.5}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_EQ(parsed.params.sensors.at(0).scan.fan.angle_increment, 0.5);
  EXPECT_EQ(parsed.params.sensors.at(0).scan.fan.samples, 0);
  EXPECT_EQ(parsed.params.sensors.at(0).scan.fan.beamCount(), 5);  // -1, -0.5, 0, 0.5, 1
}

TEST(NodeParams, WrongTypesNameTheParameterAndTheValue) {
  expectEachRefused({
      {"rate", "fast", {"~rate", "string ('fast')", "expected a number"}},
      {"range_max", true, {"~range_max", "bool (true)", "expected a number"}},
      {"samples", 100.5, {"~samples", "double (100.5)", "expected an integer"}},
      {"noise_seed", "7", {"~noise_seed", "'7'", "expected an integer"}},
      {"frame_id", 5, {"~frame_id", "int (5)", "expected a string"}},
      {"method", 1, {"~method", "int (1)", "expected a string"}},
      {"skip_bad_geometry", "yes", {"~skip_bad_geometry", "'yes'", "true or false"}},
      {"mesh_import_max_memory_mb", "2G", {"~mesh_import_max_memory_mb", "'2G'", "a number"}},
      {"cull_backfaces", 1, {"~cull_backfaces", "int (1)", "true or false"}},
      {"ignore_links", "base", {"~ignore_links", "'base'", "a list of strings"}},
      {"ignore_links", list({"a", 3}), {"~ignore_links[1]", "int (3)", "expected a string"}},
      {"models", "robot_description", {"~models", "'robot_description'", "non-empty list"}},
      {"models", list({}), {"~models", "list ([])", "non-empty list"}},
      {"reflectivity", list({0.5}), {"~reflectivity", "[0.5]", "a dict"}},
      {"reflectivity", values({{"wall", "high"}}), {"~reflectivity/wall", "'high'", "a number"}},
  });
}

TEST(NodeParams, OutOfRangeValuesNameTheParameterAndTheValue) {
  expectEachRefused({
      {"rate", 0.0, {"~rate", "(0, 1000] Hz", "got 0"}},
      {"rate", -10, {"~rate", "got -10"}},
      {"rate", 1000.5, {"~rate", "got 1000.5"}},
      {"rate", kNan, {"~rate", "got nan"}},
      {"rate", kInf, {"~rate", "got inf"}},
      {"tf_timeout", -0.1, {"~tf_timeout", "[0, 10] s", "got -0.1"}},
      {"tf_timeout", 10.5, {"~tf_timeout", "got 10.5"}},
      {"tf_timeout", kNan, {"~tf_timeout", "got nan"}},
      {"threads", -1, {"~threads", "[0, 1024]", "got -1"}},
      {"threads", 1025, {"~threads", "got 1025"}},
      {"noise_seed", -1, {"~noise_seed", "got -1"}},
      {"pose_timeout", 0.0, {"~pose_timeout", "> 0 s", "got 0"}},
      {"pose_timeout", -1, {"~pose_timeout", "got -1"}},
      {"pose_timeout", kNan, {"~pose_timeout", "got nan"}},
      {"default_reflectivity", -0.5, {"~default_reflectivity", "got -0.5"}},
      {"default_reflectivity", kInf, {"~default_reflectivity", "got inf"}},
      {"reflectivity", values({{"wall", -1}}), {"~reflectivity/wall", "got -1"}},
      {"reflectivity", values({{"wall", kNan}}), {"~reflectivity/wall", "got nan"}},
      {"mesh_import_max_memory_mb", 32, {"~mesh_import_max_memory_mb", ">= 64", "got 32"}},
      {"mesh_import_max_memory_mb", -1, {"~mesh_import_max_memory_mb", "got -1"}},
      {"mesh_import_max_memory_mb", kInf, {"~mesh_import_max_memory_mb", "got inf"}},
      {"mesh_import_timeout", -1, {"~mesh_import_timeout", "got -1"}},
      {"mesh_import_timeout", kNan, {"~mesh_import_timeout", "got nan"}},
      // Checked by the core, which names its fields as the parameters are named. FanSpec reads
      // an angle_increment or samples of 0 as unset, and asks for exactly one of the two.
      {"angle_increment", 0.0, {"~angle_increment", "angle_increment 0 rad"}},
      {"angle_increment", -0.01, {"~angle_increment", "got -0.01"}},
      {"samples", 1, {"~samples", "[2, 10000000]", "got 1"}},
      {"samples", 0, {"~samples", "samples 0)"}},
      {"range_max", -1.0, {"range_max", "-1"}},
      {"range_min", -0.5, {"range_min", "-0.5"}},
      {"noise_stddev", -0.01, {"noise_stddev", "-0.01"}},
      {"angle_min", kNan, {"angle_min", "nan"}},
      {"samples", 20000000, {"samples", "20000000"}},
  });
}

TEST(NodeParams, TheLimitsThemselvesAreAccepted) {
  expectAccepted(values({{"rate", laser_raycast::SensorParams::kMaxRate}}));
  expectAccepted(values({{"tf_timeout", NodeParams::kMaxTfTimeout}}));
  expectAccepted(values({{"tf_timeout", 0}}));
  expectAccepted(values({{"threads", 0}}));  // every core
  expectAccepted(values({{"threads", laser_raycast::core::CastConfig::kMaxThreads}}));
  expectAccepted(values({{"pose_timeout", kInf}}));  // never stale
  expectAccepted(values({{"samples", 2}}));
  expectAccepted(
      values({{"mesh_import_max_memory_mb", laser_raycast::MeshImportBounds::kMinMemoryMb},
              {"mesh_import_timeout", 1e-3}}));
  expectAccepted(values({{"noise_seed", 0}, {"default_reflectivity", 0}}));
  expectAccepted(values({{"reflectivity", values({{"black", 0}})}, {"intensity", "reflectivity"}}));
}

TEST(NodeParams, DivergentBeamsAreRefusedForBeamsOffTheGrid) {
  const std::string pattern = LASER_RAYCAST_SOURCE_DIR "/config/patterns/rosette_4line.csv";
  const std::string calibration = LASER_RAYCAST_SOURCE_DIR "/test/data/vlp16_calibration.yaml";
  expectAccepted(values({{"pattern_file", pattern}, {"point_rate", 1e5}, {"beam_samples", 1}}));
  expectRefused(values({{"pattern_file", pattern}, {"point_rate", 1e5}, {"beam_samples", 7},
                        {"beam_divergence", 0.003}}),
                {"~beam_samples", "is 7", "~pattern_file is set", "a fan or rings"});
  expectRefused(values({{"calibration_file", calibration}, {"beam_samples", 7},
                        {"beam_divergence", 0.003}}),
                {"~beam_samples", "is 7", "~calibration_file is set"});
}

TEST(NodeParams, NamesOutsideTheirTablesListTheChoices) {
  expectRefused(values({{"min_range_policy", "zero"}}),
                {"~min_range_policy", "'zero' is not one of -inf, pass_through, nan"});
  expectRefused(values({{"geometry", "hull"}}),
                {"~geometry", "'hull' is not one of visual, collision"});
  expectRefused(values({{"method", "fast"}}), {"~method", "'fast' is not one of", "watertight"});
  expectRefused(values({{"intensity", "on"}}),
                {"~intensity", "'on' is not one of off, reflectivity"});
}

TEST(NodeParams, AngleIncrementWithSamplesIsRefused) {
  expectRefused(values({{"samples", 100}, {"angle_increment", 0.01}}),
                {"~samples", "~angle_increment", "not both", "0.01", "100"});
}

TEST(NodeParams, AngleMaxNotAboveAngleMin) {
  expectRefused(values({{"angle_min", 1.0}, {"angle_max", 0.5}}),
                {"angle_max", "0.5", "angle_min", "1"});
}

TEST(NodeParams, PoseFrameWithoutPoseTopicIsRefused) {
  expectRefused(values({{"pose_frame", "base_link"}}),
                {"~pose_frame", "'base_link'", "~pose_topic is not"});
  expectAccepted(values({{"pose_frame", "base_link"}, {"pose_topic", "pose"}}));
  expectAccepted(values({{"pose_frame", ""}}));  // empty: unset
}

TEST(NodeParams, PoseTopicMustBeAValidName) {
  expectRefused(values({{"pose_topic", "my pose"}}),
                {"~pose_topic", "'my pose'", "not a valid topic name"});
  // A NodeHandle throws on a private name: refused here instead of stopping the node with an
  // uncaught exception.
  expectRefused(values({{"pose_topic", "~pose"}}), {"~pose_topic", "'~pose'", "private"});
  expectAccepted(values({{"pose_topic", "/robot/pose"}}));
  expectAccepted(values({{"pose_topic", "pose"}}));
}

TEST(NodeParams, FramesWithALeadingSlashOrEmptyAreRefused) {
  for (const char* name : {"frame_id", "fixed_frame"}) {
    SCOPED_TRACE(name);
    expectRefused(values({{name, "/odom"}}), {std::string("~") + name, "'/odom'", "'/'"});
    expectRefused(values({{name, ""}}), {std::string("~") + name, "must not be empty"});
  }
  expectRefused(values({{"pose_topic", "pose"}, {"pose_frame", "/base"}}),
                {"~pose_frame", "'/base'", "'/'"});
}

TEST(NodeParams, UnknownParametersGetAWarning) {
  const Parsed parsed = parse(values({{"angle_incremnt", 0.01}, {"rate", 20}}));
  EXPECT_EQ(parsed.error, "");
  ASSERT_EQ(parsed.report.warnings.size(), 1u);
  expectMentions(parsed.report.warnings[0], {"~angle_incremnt", "not a parameter"});
  EXPECT_EQ(parsed.params.sensors.at(0).rate, 20.0);
}

TEST(NodeParams, ReflectivityWithoutIntensityGetsAWarning) {
  const Parsed parsed = parse(values({{"reflectivity", values({{"wall", 0.5}})}}));
  EXPECT_EQ(parsed.error, "");
  ASSERT_EQ(parsed.report.warnings.size(), 1u);
  expectMentions(parsed.report.warnings[0], {"~reflectivity", "~intensity is off"});
}

TEST(NodeParams, ANamespaceThatIsNotADictIsRefused) {
  expectRefused(XmlRpcValue(5), {"namespace ~", "int (5)"});
}

TEST(NodeParams, TheFirstErrorIsReported) {
  // frame_id is read before rate.
  expectRefused(values({{"rate", -1}, {"frame_id", "/laser"}}), {"~frame_id"});
}

}  // namespace
}  // namespace laser_raycast_test
