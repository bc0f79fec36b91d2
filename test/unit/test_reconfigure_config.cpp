// cfg/Raycast.cfg against the code it configures: each live parameter's default is the node's and
// the measurement model's default, its limits are the ones they validate, the string choices are exactly the
// names they parse, and the levels say what a change touches. The generated header is compiled
// here, so a .cfg that does not generate or build fails this test.
#include <gtest/gtest.h>
#include <laser_raycast/RaycastConfig.h>

#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/node/node_params.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::RaycastConfig;
using laser_raycast::core::MeasurementConfig;

std::map<std::string, RaycastConfig::AbstractParamDescriptionConstPtr> descriptions() {
  std::map<std::string, RaycastConfig::AbstractParamDescriptionConstPtr> out;
  for (const auto& d : RaycastConfig::__getParamDescriptions__()) out[d->name] = d;
  return out;
}

TEST(ReconfigureConfig, TheLiveParameters) {
  std::map<std::string, RaycastConfig::AbstractParamDescriptionConstPtr> d = descriptions();
  std::string names;
  for (const auto& entry : d) names += entry.first + " ";
  EXPECT_EQ(names,
            "dropout_probability intensity min_range_policy noise_seed noise_stddev range_bias "
            "range_max range_min range_resolution rate ");
}

TEST(ReconfigureConfig, DefaultsAreTheNodes) {
  const RaycastConfig& def = RaycastConfig::__getDefault__();
  const MeasurementConfig model;
  const laser_raycast::SensorParams sensor;
  EXPECT_EQ(def.rate, sensor.rate);
  EXPECT_EQ(def.range_min, model.range_min);
  EXPECT_EQ(def.range_max, model.range_max);
  EXPECT_EQ(def.min_range_policy, toString(model.min_range_policy));
  EXPECT_EQ(def.intensity, laser_raycast::kIntensityNames.name(model.intensity));
  EXPECT_EQ(def.noise_stddev, model.noise_stddev);
  EXPECT_EQ(static_cast<std::uint64_t>(def.noise_seed), model.noise_seed);
  EXPECT_EQ(def.range_bias, model.range_bias);
  EXPECT_EQ(def.range_resolution, model.range_resolution);
  EXPECT_EQ(def.dropout_probability, model.dropout_probability);
}

TEST(ReconfigureConfig, LimitsAreTheValidatedOnes) {
  const RaycastConfig& min = RaycastConfig::__getMin__();
  const RaycastConfig& max = RaycastConfig::__getMax__();
  EXPECT_EQ(max.rate, laser_raycast::SensorParams::kMaxRate);
  EXPECT_EQ(min.rate, 0.0);  // exclusive in the node, which refuses 0
  EXPECT_EQ(min.range_min, 0.0);
  EXPECT_EQ(min.noise_stddev, 0.0);
  EXPECT_EQ(min.noise_seed, 0);
  EXPECT_EQ(min.range_resolution, 0.0);
  EXPECT_EQ(min.dropout_probability, 0.0);
  EXPECT_EQ(max.dropout_probability, 1.0);
  // Unbounded where the node is (no slider limit may clamp a value the node accepts).
  EXPECT_EQ(max.range_max, std::numeric_limits<double>::infinity());
  EXPECT_EQ(max.noise_stddev, std::numeric_limits<double>::infinity());
  EXPECT_EQ(min.range_bias, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(max.range_bias, std::numeric_limits<double>::infinity());
}

// The edit_method of a string enum lists its values as 'value': '<name>'.
void expectChoicesExactly(const std::string& edit_method, const std::vector<std::string>& names) {
  std::size_t count = 0;
  for (std::size_t at = edit_method.find("'value': "); at != std::string::npos;
       at = edit_method.find("'value': ", at + 1)) {
    ++count;
  }
  EXPECT_EQ(count, names.size()) << edit_method;
  for (const std::string& name : names) {
    EXPECT_NE(edit_method.find("'value': '" + name + "'"), std::string::npos)
        << name << " in " << edit_method;
  }
}

TEST(ReconfigureConfig, ChoicesAreTheParsedNames) {
  auto d = descriptions();
  std::vector<std::string> policies, intensities;
  for (const auto& entry : laser_raycast::core::kMinRangePolicyNames.entries()) {
    policies.push_back(entry.second);
  }
  for (const auto& entry : laser_raycast::kIntensityNames.entries()) {
    intensities.push_back(entry.second);
  }
  expectChoicesExactly(d.at("min_range_policy")->edit_method, policies);
  expectChoicesExactly(d.at("intensity")->edit_method, intensities);
  EXPECT_STREQ(laser_raycast::Raycast_neg_inf, "-inf");
  EXPECT_STREQ(laser_raycast::Raycast_reflectivity, "reflectivity");
}

// 1: the measurement model only; 2: also the cast; 4: the timer.
TEST(ReconfigureConfig, Levels) {
  auto d = descriptions();
  for (const char* name :
       {"noise_stddev", "noise_seed", "range_bias", "range_resolution", "dropout_probability"}) {
    EXPECT_EQ(d.at(name)->level, 1u) << name;
  }
  for (const char* name : {"range_min", "range_max", "min_range_policy", "intensity"}) {
    EXPECT_EQ(d.at(name)->level, 3u) << name;
  }
  EXPECT_EQ(d.at("rate")->level, 4u);
}

}  // namespace
}  // namespace laser_raycast_test
