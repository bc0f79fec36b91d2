// The sensor parameters beyond a planar instantaneous scan, parsed as the node parses them (no
// parameter server, no roscore): rings, sweeps, range realism, presets, Ouster metadata files and
// the sensors list, each value reaching its field and each bad one refused naming the parameter
// (or the entry) and the value.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/node/node_params.h"
#include "node_params_inputs.h"
#include "vlp16_manual.h"

namespace laser_raycast_test {
namespace {

using XmlRpc::XmlRpcValue;

const double kNan = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

TEST(SensorParams, ThreeDSweepAndRealismValuesReachTheirFields) {
  const Parsed parsed = parse(values({{"elevations", list({0.1, -0.2, 0})},  // any order
                                      {"sweep", "rotating"},
                                      {"rate", 10},
                                      {"scan_time", 0.05},
                                      {"organized", true},
                                      {"range_bias", -0.02},
                                      {"range_resolution", 0.002},
                                      {"dropout_probability", 0.1}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_TRUE(parsed.report.warnings.empty()) << parsed.report.warnings.front();
  const laser_raycast::SensorParams& s = parsed.params.sensors.at(0);
  EXPECT_EQ(s.scan.elevations, (std::vector<double>{0.1, -0.2, 0}));
  EXPECT_FALSE(s.planar());
  EXPECT_EQ(s.topic, "points");
  EXPECT_EQ(s.sweep, laser_raycast::Sweep::kRotating);
  EXPECT_EQ(s.scan_time, 0.05);
  EXPECT_TRUE(s.organized);
  EXPECT_EQ(s.scan.output.range_bias, -0.02);
  EXPECT_EQ(s.scan.output.range_resolution, 0.002);
  EXPECT_EQ(s.scan.output.dropout_probability, 0.1);
  // 360 beams from -pi to pi: 2 pi / 359 apart; the head turns 2 pi in 0.05 s.
  EXPECT_NEAR(s.timeIncrement(), 0.05 / 359, 1e-15);
  EXPECT_NEAR(s.sweepDuration(), 0.05, 1e-15);
}

TEST(SensorParams, ARotatingScanTurnsOncePerScanTimeOrPeriod) {
  const Parsed parsed = parse(values({{"sweep", "rotating"}, {"rate", 20}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_EQ(parsed.params.sensors.at(0).scanTime(), 0.05);  // 1 / rate
  expectRefused(values({{"sweep", "rotating"}, {"rate", 10}, {"scan_time", 0.2}}),
                {"~scan_time", "(0, 0.1] s", "got 0.2"});
  expectRefused(values({{"sweep", "rotating"}, {"scan_time", 0}}), {"~scan_time", "got 0"});
  expectRefused(values({{"sweep", "spinning"}}),
                {"~sweep", "'spinning' is not one of instant, rotating"});
  const Parsed instant = parse(values({{"scan_time", 0.05}}));
  ASSERT_EQ(instant.report.warnings.size(), 1u);
  expectMentions(instant.report.warnings[0], {"~scan_time", "no effect", "instant"});
  const Parsed organized = parse(values({{"organized", true}}));
  ASSERT_EQ(organized.report.warnings.size(), 1u);
  expectMentions(organized.report.warnings[0], {"~organized", "planar"});
}

TEST(SensorParams, BadElevationsNameTheParameterAndTheValue) {
  expectRefused(values({{"elevations", list({})}}), {"~elevations", "must not be empty"});
  expectRefused(values({{"elevations", list({0.1, kNan})}}), {"~elevations[1]", "got nan"});
  expectRefused(values({{"elevations", list({0.1, kInf})}}), {"~elevations[1]", "got inf"});
  expectRefused(values({{"elevations", list({0.1, "up"})}}), {"~elevations[1]", "'up'"});
  expectRefused(values({{"elevations", 0.1}}), {"~elevations", "a list of numbers"});
  // Checked by the core: within [-pi/2, pi/2], distinct.
  expectRefused(values({{"elevations", list({2.0})}}), {"elevations", "2"});
  expectRefused(values({{"elevations", list({0.1, 0.1})}}), {"elevations", "0.1"});
}

// The VLP-16's datasheet: 16 rings every 2 deg from -15 to +15, 0.2 deg at 10 Hz, up to 100 m.
TEST(SensorParams, APresetSetsThePatternRangesAndRateAndExplicitValuesWin) {
  Parsed parsed = parse(values({{"sensor_model", "VLP-16"}}));
  ASSERT_EQ(parsed.error, "");
  const laser_raycast::SensorParams& s = parsed.params.sensors.at(0);
  ASSERT_EQ(s.scan.elevations.size(), 16u);
  EXPECT_NEAR(s.scan.elevations.front(), -15 * M_PI / 180, 1e-12);
  EXPECT_NEAR(s.scan.elevations.back(), 15 * M_PI / 180, 1e-12);
  EXPECT_NEAR(s.scan.fan.increment(), 0.2 * M_PI / 180, 1e-12);
  EXPECT_EQ(s.scan.fan.beamCount(), 1800);
  EXPECT_EQ(s.scan.output.range_max, 100.0);
  EXPECT_EQ(s.rate, 10.0);
  EXPECT_EQ(s.topic, "points");

  parsed = parse(
      values({{"sensor_model", "VLP-16"}, {"range_max", 50}, {"rate", 20}, {"samples", 900}}));
  ASSERT_EQ(parsed.error, "");
  const laser_raycast::SensorParams& t = parsed.params.sensors.at(0);
  EXPECT_EQ(t.scan.output.range_max, 50.0);
  EXPECT_EQ(t.scan.output.range_min, 0.4);  // the preset's
  EXPECT_EQ(t.rate, 20.0);
  EXPECT_EQ(t.scan.fan.samples, 900);
  EXPECT_EQ(t.scan.fan.angle_increment, 0.0);
  EXPECT_EQ(t.scan.elevations.size(), 16u);

  // A planar preset keeps the LaserScan.
  parsed = parse(values({{"sensor_model", "LDS-01"}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_TRUE(parsed.params.sensors.at(0).planar());
  EXPECT_EQ(parsed.params.sensors.at(0).scan.fan.beamCount(), 360);
  EXPECT_EQ(parsed.params.sensors.at(0).scan.output.range_max, 3.5);
}

// The Velodyne presets fire their lasers as the user manuals say: one turn of firing sequences at
// the sensor's rate (VLP-16: a sequence of 16 every 55.296 us, 2.304 us apart; HDL-32E: 32 every
// 46.08 us, 1.152 us apart), rings by ascending elevation. Setting the fan, the elevations or
// divergent beams makes the preset the grid of its elevations, and says so; a calibration file
// gives its own lasers. The OS1-64 fires as its nominal metadata file in the package says.
TEST(SensorParams, TheLidarPresetsFireTheirLasersAsTheirMakersSay) {
  Parsed parsed = parse(values({{"sensor_model", "VLP-16"}}));
  ASSERT_EQ(parsed.error, "");
  const laser_raycast::SensorParams& s = parsed.params.sensors.at(0);
  ASSERT_TRUE(s.calibrated);
  EXPECT_TRUE(s.preset_head);
  EXPECT_EQ(s.calibratedFrom(), "the VLP-16 preset's lasers");
  const int sequences = static_cast<int>(0.1 / 55.296e-6);  // 1808
  ASSERT_EQ(s.calibrated->size(), 16 * sequences);
  // Laser id i of sequence q: its elevation from the manual's table, its ring by elevation, its
  // time q * 55.296 + i * 2.304 us, its azimuth the head's then (pi at 0, clockwise, a turn in
  // 0.1 s).
  const int table[16] = {-15, 1, -13, 3, -11, 5, -9, 7, -7, 9, -5, 11, -3, 13, -1, 15};
  for (int q : {0, 1, 903, sequences - 1}) {
    for (int i = 0; i < 16; ++i) {
      const int b = q * 16 + i;
      const Eigen::Vector3d& d = s.calibrated->directions[b];
      const double t = vlp16FiringTime(q, i);
      EXPECT_NEAR(std::asin(d.z()), table[i] * M_PI / 180, 1e-12) << b;
      EXPECT_EQ(s.calibrated->line(b), (table[i] + 15) / 2) << b;
      EXPECT_NEAR(s.calibrated->time(b), t, 1e-15) << b;
      EXPECT_NEAR(std::remainder(std::atan2(d.y(), d.x()) - vlp16HeadAzimuth(t, 0.1), 2 * M_PI),
                  0.0, 1e-12)
          << b;
      EXPECT_EQ(s.calibrated->origin(b), Eigen::Vector3d::Zero()) << b;
    }
  }
  EXPECT_NEAR(s.sweepDuration(), 0.0, 0.0);  // instant: every beam cast at the stamp

  // A rotating VLP-16 at 20 Hz turns in 0.05 s: half the sequences.
  parsed = parse(values({{"sensor_model", "VLP-16"}, {"rate", 20}, {"sweep", "rotating"}}));
  ASSERT_EQ(parsed.error, "");
  const laser_raycast::SensorParams& fast = parsed.params.sensors.at(0);
  ASSERT_TRUE(fast.calibrated);
  EXPECT_EQ(fast.calibrated->size(), 16 * static_cast<int>(0.05 / 55.296e-6));
  EXPECT_NEAR(fast.sweepDuration(), fast.calibrated->times.back(), 0.0);

  parsed = parse(values({{"sensor_model", "HDL-32E"}}));
  ASSERT_EQ(parsed.error, "");
  const laser_raycast::SensorParams& hdl = parsed.params.sensors.at(0);
  ASSERT_TRUE(hdl.calibrated);
  EXPECT_EQ(hdl.calibrated->size(), 32 * static_cast<int>(0.1 / 46.08e-6));
  EXPECT_NEAR(hdl.calibrated->time(1), 1.152e-6, 1e-15);
  EXPECT_NEAR(std::asin(hdl.calibrated->directions[0].z()), -30.67 * M_PI / 180, 1e-12);
  EXPECT_EQ(hdl.calibrated->line(0), 0);    // the lowest laser
  EXPECT_EQ(hdl.calibrated->line(31), 31);  // the highest, +10.67 deg

  // Set explicitly, the fan, elevations or divergent beams give the grid, with a note.
  for (const auto& [name, value] :
       std::vector<std::pair<std::string, XmlRpcValue>>{{"samples", XmlRpcValue(900)},
                                                        {"angle_min", XmlRpcValue(-1.0)},
                                                        {"elevations", list({-0.1, 0.1})},
                                                        {"beam_samples", XmlRpcValue(7)}}) {
    XmlRpcValue v = values({{"sensor_model", "VLP-16"}});
    v[name] = value;
    if (name == "beam_samples") v["beam_divergence"] = 0.003;
    parsed = parse(v);
    ASSERT_EQ(parsed.error, "") << name;
    const laser_raycast::SensorParams& grid = parsed.params.sensors.at(0);
    EXPECT_FALSE(grid.calibrated) << name;
    EXPECT_FALSE(grid.preset_head) << name;
    const auto& log = parsed.report.values;
    const std::string why = name == "beam_samples" ? "~beam_samples is 7" : "~" + name + " is set";
    EXPECT_NE(std::find(log.begin(), log.end(),
                        why + ": VLP-16's lasers as a grid (every ring at the same azimuths, a " +
                            "column at once)"),
              log.end())
        << name;
  }
  // A calibration file's lasers, not the preset's.
  parsed = parse(
      values({{"sensor_model", "VLP-16"},
              {"calibration_file", LASER_RAYCAST_SOURCE_DIR "/test/data/vlp16_calibration.yaml"}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_TRUE(parsed.params.sensors.at(0).calibrated);
  EXPECT_FALSE(parsed.params.sensors.at(0).preset_head);
  // The OS1-64's from the nominal metadata file in the package: 1024 columns of 64 rows, each
  // column at its own time; its realistic variant's seven sub-rays a beam make it the grid.
  parsed = parse(values({{"sensor_model", "OS1-64"}}));
  ASSERT_EQ(parsed.error, "");
  const laser_raycast::SensorParams& os1 = parsed.params.sensors.at(0);
  ASSERT_TRUE(os1.calibrated);
  EXPECT_TRUE(os1.preset_head);
  EXPECT_EQ(os1.calibrated->size(), 64 * 1024);
  EXPECT_NEAR(os1.calibrated->time(64), 0.1 / 1024, 1e-15);  // column 1's first row
  EXPECT_EQ(os1.calibrated->line(0), 0);
  parsed = parse(values({{"sensor_model", "OS1-64-realistic"}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_FALSE(parsed.params.sensors.at(0).calibrated);
  const auto& log = parsed.report.values;
  EXPECT_NE(std::find(log.begin(), log.end(),
                      "~beam_samples is 7: OS1-64-realistic's lasers as a grid (every ring at the "
                      "same azimuths, a column at once)"),
            log.end());
  // Planar presets stay fans.
  for (const char* name : {"UTM-30LX", "TiM571", "LDS-01"}) {
    parsed = parse(values({{"sensor_model", name}}));
    ASSERT_EQ(parsed.error, "") << name;
    EXPECT_FALSE(parsed.params.sensors.at(0).calibrated) << name;
    EXPECT_TRUE(parsed.params.sensors.at(0).planar()) << name;
  }
}

TEST(SensorParams, AnUnknownPresetNamesTheChoices) {
  expectRefused(values({{"sensor_model", "VLP-15"}}), {"~sensor_model", "'VLP-15' is not one of",
                                                       "VLP-16", "LDS-01", "OS1-64-realistic"});
  expectRefused(values({{"sensor_model", "LDS-01-realistic"}}),
                {"~sensor_model", "'LDS-01-realistic'", "no realistic variant"});
}

// A realistic variant: the preset's pattern with its datasheet's detection pair, divergence and
// return; explicit values still win.
TEST(SensorParams, ARealisticVariantSetsTheDetectionPairDivergenceAndReturn) {
  Parsed parsed = parse(values({{"sensor_model", "OS1-64-realistic"}}));
  ASSERT_EQ(parsed.error, "");
  const laser_raycast::SensorParams& s = parsed.params.sensors.at(0);
  EXPECT_EQ(s.scan.elevations.size(), 64u);
  EXPECT_EQ(s.scan.output.detection_range, 40.0);
  EXPECT_EQ(s.scan.output.detection_reflectivity, 0.1);
  EXPECT_NEAR(s.returns.beam_divergence, 0.13 * M_PI / 180, 1e-15);
  EXPECT_EQ(s.returns.beam_samples, 7);
  EXPECT_EQ(s.returns.min_return_separation, 0.012);

  parsed = parse(values({{"sensor_model", "OS1-64-realistic"},
                         {"detection_range", 50.0},
                         {"beam_samples", 1},
                         {"return_mode", "dual"}}));
  ASSERT_EQ(parsed.error, "");
  const laser_raycast::SensorParams& t = parsed.params.sensors.at(0);
  EXPECT_EQ(t.scan.output.detection_range, 50.0);
  EXPECT_EQ(t.scan.output.detection_reflectivity, 0.1);  // the variant's
  EXPECT_EQ(t.returns.beam_samples, 1);
  EXPECT_EQ(t.returns.return_mode, laser_raycast::core::ReturnMode::kDual);

  parsed = parse(values({{"sensor_model", "OS1-64"}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_EQ(parsed.params.sensors.at(0).scan.output.detection_range, 0.0);
  EXPECT_EQ(parsed.params.sensors.at(0).returns.beam_samples, 1);
}

XmlRpcValue sensor(const std::vector<std::pair<std::string, XmlRpcValue>>& entries) {
  return values(entries);
}

// The private namespace's sensor parameters are every entry's defaults; an entry's own preset and
// keys override them.
// ~point_layout: velodyne by default, per entry of ~sensors with the private namespace's as the
// default; a value not in the table names the choices; a layout whose integer fields cannot hold
// the scan's rings or point times is refused at start-up.
TEST(SensorParams, PointLayoutPerSensor) {
  using laser_raycast::PointLayout;
  const Parsed parsed = parse(
      values({{"point_layout", "ouster"},
              {"elevations", list({-0.1, 0.1})},
              {"sensors", list({sensor({{"frame_id", "a"}}),
                                sensor({{"frame_id", "b"}, {"point_layout", "ouster_legacy"}}),
                                sensor({{"frame_id", "c"}, {"point_layout", "livox"}}),
                                sensor({{"frame_id", "d"}, {"point_layout", "hesai"}}),
                                sensor({{"frame_id", "e"}, {"point_layout", "velodyne"}})})}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_TRUE(parsed.report.warnings.empty()) << parsed.report.warnings.front();
  const std::vector<PointLayout> expected = {PointLayout::kOuster, PointLayout::kOusterLegacy,
                                             PointLayout::kLivox, PointLayout::kHesai,
                                             PointLayout::kVelodyne};
  ASSERT_EQ(parsed.params.sensors.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(parsed.params.sensors[i].point_layout, expected[i]) << i;
  }
  const auto& log = parsed.report.values;
  EXPECT_NE(std::find(log.begin(), log.end(), "~sensors[2]/point_layout = 'livox'"), log.end());
  EXPECT_EQ(parse(values({})).params.sensors.at(0).point_layout, PointLayout::kVelodyne);

  expectRefused(values({{"point_layout", "xyzirt"}}),
                {"~point_layout",
                 "'xyzirt' is not one of velodyne, ouster, ouster_legacy, livox, "
                 "hesai"});
  expectRefused(values({{"sensors", list({sensor({{"frame_id", "a"}, {"point_layout", 3}})})}}),
                {"~sensors[0]/point_layout", "is a int (3)", "a string"});
  // 300 rings do not fit a uint8 ring; a 5 s sweep does not fit ouster's uint32 ns.
  std::vector<XmlRpcValue> many;
  for (int i = 0; i < 300; ++i) many.push_back(-1.5 + i * 0.01);
  expectRefused(values({{"elevations", list(many)}, {"point_layout", "ouster_legacy"}}),
                {"~point_layout", "'ouster_legacy'", "at most 256", "300 rings"});
  expectAccepted(values({{"elevations", list(many)}, {"point_layout", "ouster"}}));
  expectRefused(values({{"elevations", list({0.1})},
                        {"point_layout", "ouster"},
                        {"sweep", "rotating"},
                        {"rate", 0.2}}),
                {"~point_layout", "'ouster'", "uint32 ns", "the sweep lasts 4.99"});
  // A planar sensor publishes a LaserScan: the layout has no effect.
  const Parsed planar = parse(values({{"point_layout", "ouster"}}));
  ASSERT_EQ(planar.report.warnings.size(), 1u);
  expectMentions(planar.report.warnings[0], {"~point_layout", "planar"});
}

// ~ouster_metadata: the file's beams (a turn of scan_time), one of the three beam files, a warning
// when the node's turn is not the lidar mode's, a bad file refused naming the parameter.
TEST(SensorParams, OusterMetadata) {
  const std::string file = LASER_RAYCAST_SOURCE_DIR "/config/ouster/os1_64_nominal.json";
  const Parsed parsed = parse(values({{"ouster_metadata", file}, {"sweep", "rotating"}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_TRUE(parsed.report.warnings.empty()) << parsed.report.warnings.front();
  const laser_raycast::SensorParams& s = parsed.params.sensors.at(0);
  ASSERT_TRUE(s.calibrated);
  EXPECT_EQ(s.calibrated->size(), 64 * 1024);
  EXPECT_EQ(s.calibratedFrom(), file);
  EXPECT_FALSE(s.planar());
  EXPECT_NEAR(s.sweepDuration(), 0.1 * 1023 / 1024, 1e-15);  // the last column's time
  const Parsed fast = parse(values({{"ouster_metadata", file}, {"rate", 20}}));
  ASSERT_EQ(fast.error, "");
  ASSERT_EQ(fast.report.warnings.size(), 1u);
  expectMentions(fast.report.warnings[0], {"~ouster_metadata", "10 Hz", "0.05 s"});
  EXPECT_NEAR(fast.params.sensors.at(0).calibrated->times.back(), 0.05 * 1023 / 1024, 1e-15);
  expectRefused(
      values({{"ouster_metadata", file},
              {"calibration_file", LASER_RAYCAST_SOURCE_DIR "/test/data/vlp16_calibration.yaml"}}),
      {"~ouster_metadata", "~calibration_file: give one"});
  expectRefused(
      values({{"ouster_metadata", file},
              {"pattern_file", LASER_RAYCAST_SOURCE_DIR "/config/patterns/rosette_4line.csv"},
              {"point_rate", 1000}}),
      {"~ouster_metadata", "~pattern_file: give one"});
  expectRefused(values({{"ouster_metadata", file}, {"beam_samples", 4}}),
                {"~beam_samples", "~ouster_metadata is set"});
  expectRefused(values({{"ouster_metadata", "/nonexistent/os.json"}}),
                {"~ouster_metadata", "/nonexistent/os.json"});
}

TEST(SensorParams, SeveralSensors) {
  const Parsed parsed =
      parse(values({{"noise_stddev", 0.01},
                    {"rate", 20},
                    {"sensors", list({sensor({{"frame_id", "front"}, {"samples", 100}}),
                                      sensor({{"name", "top"},
                                              {"frame_id", "velodyne"},
                                              {"sensor_model", "VLP-16"},
                                              {"topic", "velodyne_points"}})})}}));
  ASSERT_EQ(parsed.error, "");
  EXPECT_TRUE(parsed.report.warnings.empty()) << parsed.report.warnings.front();
  ASSERT_EQ(parsed.params.sensors.size(), 2u);
  const laser_raycast::SensorParams& front = parsed.params.sensors[0];
  EXPECT_EQ(front.name, "front");
  EXPECT_EQ(front.frame_id, "front");
  EXPECT_EQ(front.topic, "front/scan");
  EXPECT_EQ(front.labelsTopic(), "front/scan_labels");
  EXPECT_EQ(front.scan.fan.samples, 100);
  EXPECT_EQ(front.rate, 20.0);
  EXPECT_EQ(front.scan.output.noise_stddev, 0.01);
  const laser_raycast::SensorParams& top = parsed.params.sensors[1];
  EXPECT_EQ(top.name, "top");
  EXPECT_EQ(top.topic, "velodyne_points");
  EXPECT_EQ(top.rate, 10.0);  // the entry's preset over the namespace's rate
  EXPECT_EQ(top.scan.elevations.size(), 16u);
  EXPECT_EQ(top.scan.output.noise_stddev, 0.01);
  const auto& log = parsed.report.values;
  EXPECT_NE(std::find(log.begin(), log.end(), "~sensors[1]/sensor_model = 'VLP-16'"), log.end());
}

TEST(SensorParams, BadSensorsEntriesNameTheEntry) {
  const auto two = [](const XmlRpcValue& second) {
    return values({{"sensors", list({sensor({{"frame_id", "a"}}), second})}});
  };
  expectRefused(two(sensor({{"samples", 10}})), {"~sensors[1]/frame_id", "not set"});
  expectRefused(two(sensor({{"frame_id", "b"}, {"topic", "a/scan"}})),
                {"~sensors[1]/topic", "'a/scan'", "~sensors[0]"});
  expectRefused(two(sensor({{"frame_id", "b"}, {"topic", "a/scan_labels"}})),
                {"~sensors[1]/topic", "'a/scan_labels'", "~sensors[0]"});
  expectRefused(two(sensor({{"frame_id", "b"}, {"name", "a"}})),
                {"~sensors[1]/name", "'a'", "~sensors[0]"});
  expectRefused(two(sensor({{"frame_id", "b"}, {"rate", -1}})), {"~sensors[1]/rate", "got -1"});
  expectRefused(two(sensor({{"frame_id", "b"}, {"sensor_model", "X"}})),
                {"~sensors[1]/sensor_model", "'X'"});
  expectRefused(two(sensor({{"frame_id", "b"}, {"elevations", list({})}})),
                {"~sensors[1]/elevations", "empty"});
  expectRefused(two(sensor({{"frame_id", "b"}, {"range_min", 5}, {"range_max", 1}})),
                {"~sensors[1]/range_max", "(1 m)", "(5 m)"});
  expectRefused(two(sensor({{"frame_id", "b"}, {"name", "b/c"}})), {"~sensors[1]/name", "'b/c'"});
  expectRefused(two(XmlRpcValue("b")), {"~sensors[1]", "'b'", "a dict"});
  expectRefused(values({{"sensors", list({})}}), {"~sensors", "non-empty list"});
  expectRefused(values({{"sensors", "front"}}), {"~sensors", "non-empty list"});
}

// An entry without a name is named after its frame_id, made a valid name without '/' (it names the
// namespace of the sensor's live parameters and the default topic).
TEST(SensorParams, TheDefaultNameIsAValidNameMadeFromTheFrame) {
  const Parsed parsed = parse(values({{"sensors", list({sensor({{"frame_id", "r1/laser"}}),
                                                        sensor({{"frame_id", "2d-lidar.front"}}),
                                                        sensor({{"frame_id", "top"}})})}}));
  ASSERT_EQ(parsed.error, "");
  ASSERT_EQ(parsed.params.sensors.size(), 3u);
  EXPECT_EQ(parsed.params.sensors[0].name, "r1_laser");
  EXPECT_EQ(parsed.params.sensors[0].frame_id, "r1/laser");
  EXPECT_EQ(parsed.params.sensors[0].topic, "r1_laser/scan");
  EXPECT_EQ(parsed.params.sensors[1].name, "sensor_2d_lidar_front");
  EXPECT_EQ(parsed.params.sensors[2].name, "top");
  const auto& log = parsed.report.values;
  EXPECT_NE(std::find(log.begin(), log.end(), "~sensors[0]/name unset: 'r1_laser' (from frame_id)"),
            log.end());
  // Its live parameters (~r1_laser) are not taken for a typo.
  const Parsed live = parse(values({{"sensors", list({sensor({{"frame_id", "r1/laser"}})})},
                                    {"r1_laser", values({{"rate", 5}})}}));
  ASSERT_EQ(live.error, "");
  EXPECT_TRUE(live.report.warnings.empty()) << live.report.warnings.front();
  // Two frames that give one name are refused as any two equal names are.
  expectRefused(values({{"sensors", list({sensor({{"frame_id", "r1/laser"}}),
                                          sensor({{"frame_id", "r1_laser"}})})}}),
                {"~sensors[1]/name", "'r1_laser' is also the name of ~sensors[0]"});
  // A name given explicitly is not changed.
  expectRefused(values({{"sensors", list({sensor({{"frame_id", "a"}, {"name", "r1/laser"}})})}}),
                {"~sensors[0]/name", "'r1/laser'"});
}

// Topics are compared as the node advertises them, resolved in its namespace: "scan" and "/scan"
// are one topic in the root namespace, not in /robot, where "scan" is "/robot/scan".
TEST(SensorParams, DuplicateTopicsAreFoundAfterResolving) {
  const auto two = [](const std::string& a, const std::string& b) {
    return values({{"sensors", list({sensor({{"frame_id", "a"}, {"topic", a}}),
                                     sensor({{"frame_id", "b"}, {"topic", b}})})}});
  };
  expectRefused(two("scan", "/scan"), {"~sensors[1]/topic", "'/scan' publishes on /scan",
                                       "as ~sensors[0] does ('scan')"});
  expectRefused(two("/scan", "scan"), {"~sensors[1]/topic", "'scan' publishes on /scan"});
  expectRefused(two("a//scan/", "/a/scan"), {"~sensors[1]/topic", "/a/scan"});
  expectAccepted(two("scan", "/scan"), "/robot");
  expectRefused(two("scan", "/robot/scan"), {"publishes on /robot/scan", "namespace /robot"},
                "/robot");
  // The labels' topics too: "/a_labels" is sensor a's labels topic.
  expectRefused(two("a", "/a_labels"),
                {"~sensors[1]/topic", "'/a_labels' publishes on /a_labels", "('a_labels')"});
  // A default topic (a/scan: <name>/scan) against an explicit global one.
  expectRefused(values({{"sensors", list({sensor({{"frame_id", "a"}}),
                                          sensor({{"frame_id", "b"}, {"topic", "/a/scan"}})})}}),
                {"~sensors[1]/topic", "'/a/scan' publishes on /a/scan", "('a/scan')"});
  EXPECT_THROW(parse(values({}), "robot"), std::invalid_argument);
}

// A NodeHandle refuses private names: such a topic would stop the node with an exception at
// start-up, not with a message naming the parameter.
TEST(SensorParams, PrivateTopicNamesAreRefused) {
  expectRefused(values({{"sensors", list({sensor({{"frame_id", "a"}, {"topic", "~scan"}})})}}),
                {"~sensors[0]/topic", "'~scan'", "private"});
  expectRefused(values({{"pose_topic", "~pose"}}), {"~pose_topic", "'~pose'", "private"});
  expectRefused(values({{"sensors", list({sensor({{"frame_id", "a"}, {"pose_topic", "~p"}})})}}),
                {"~sensors[0]/pose_topic", "'~p'", "private"});
}

TEST(SensorParams, SensorsEntriesWarnAboutUnknownKeysButNotTheirLiveParameters) {
  const Parsed parsed =
      parse(values({{"sensors", list({sensor({{"frame_id", "a"}, {"sampels", 5}})})},
                    {"a", values({{"rate", 10}})}}));
  ASSERT_EQ(parsed.error, "");
  ASSERT_EQ(parsed.report.warnings.size(), 1u) << parsed.report.warnings.back();
  expectMentions(parsed.report.warnings[0], {"~sensors[0]/sampels", "not a sensor parameter"});
}

}  // namespace
}  // namespace laser_raycast_test
