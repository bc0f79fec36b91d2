// From geometry to what the sensor reports (REP 117): the min-range policy, +-Inf and NaN, Gaussian
// noise, intensity, and one rounding to float.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/enum_names.h"

namespace laser_raycast {
namespace core {

// What a surface closer than range_min gives.
enum class MinRangePolicy {
  kNegInf,       // "-inf": the beam reports -Inf (REP 117: too close). The default.
  kPassThrough,  // "pass_through": such surfaces are invisible; the beam reports what lies beyond
                 // them
  kNan,          // "nan": the beam reports NaN (erroneous), as some drivers do
};
inline const EnumNames<MinRangePolicy, 3> kMinRangePolicyNames{{{
    {MinRangePolicy::kNegInf, "-inf"},
    {MinRangePolicy::kPassThrough, "pass_through"},
    {MinRangePolicy::kNan, "nan"},
}}};
inline const char* toString(MinRangePolicy policy) { return kMinRangePolicyNames.name(policy); }
inline bool parseMinRangePolicy(const std::string& name, MinRangePolicy* policy) {
  return kMinRangePolicyNames.parse(name, policy);
}

struct EncoderConfig {
  double range_min = 0.0;   // m, >= 0
  double range_max = 30.0;  // m, > range_min
  MinRangePolicy min_range_policy = MinRangePolicy::kNegInf;
  double noise_stddev = 0.0;  // m, >= 0: Gaussian noise added to valid ranges
  std::uint64_t noise_seed =
      0;                   // seed of the noise generator: equal seeds give equal noise sequences
  bool intensity = false;  // fill intensities: reflectivity of the link hit x cos(incidence angle)

  // Throws std::invalid_argument naming the field and its value.
  void validate() const;
};

// REP 117 for one noise-free range from the caster: a hit in [range_min, range_max] is itself, a
// hit closer than range_min follows the policy, no hit is +Inf, NaN stays NaN. Under pass_through
// the cast starts at range_min (ScanSpec::castConfig), so no closer range comes from it; one passed
// anyway is +Inf.
double classifyRange(double range, const EncoderConfig& config);

struct EncodedScan {
  std::vector<float> ranges;       // REP 117
  std::vector<float> intensities;  // one per beam when EncoderConfig::intensity, else empty
  std::vector<int> labels;         // label index of the body hit (also when too close), -1 for none
};

class ScanEncoder {
 public:
  explicit ScanEncoder(const EncoderConfig& config);  // validates

  // Valid ranges get N(0, noise_stddev) noise, clamped to [range_min, range_max] so that a valid
  // return stays valid, then are rounded once to float. Noise is drawn afresh on every call.
  // reflectivity is indexed by label (missing entries count as 1); intensity needs
  // result.cos_incidence.
  void encode(const Scene& scene, const ScanResult& result, const std::vector<double>& reflectivity,
              EncodedScan* out);

 private:
  EncoderConfig config_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_;
};

}  // namespace core
}  // namespace laser_raycast
