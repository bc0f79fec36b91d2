// From geometry to what the sensor reports (REP 117): the min-range policy, +-Inf and NaN, the
// range realism options (bias, Gaussian noise, quantisation, dropout), intensity, and one rounding
// to float.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/enum_names.h"
#include "laser_raycast/core/surface_reflectance.h"

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

struct MeasurementConfig {
  double range_min = 0.0;   // m, >= 0
  double range_max = 30.0;  // m, > range_min
  MinRangePolicy min_range_policy = MinRangePolicy::kNegInf;
  double noise_stddev = 0.0;  // m, >= 0: Gaussian noise added to valid ranges
  // Seed of the random draws (noise and dropout): equal seeds give equal sequences.
  std::uint64_t noise_seed = 0;
  bool intensity = false;  // fill intensities: reflectivity of the link hit x cos(incidence angle)
  // With intensity: the reflectance and incidence come from the mesh hit where it has colours, a
  // texture, a material colour or vertex normals (surface_reflectance.h), unless the link's
  // reflectivity is set explicitly.
  bool surface_reflectance = true;
  double reflectance_from_color = 1.0;  // >= 0: the reflectance of a white surface
  // Range realism, off by default; like the noise, only valid returns get it (see MeasurementModel).
  double range_bias = 0.0;        // m, finite: added to every valid range (a calibration offset)
  double range_resolution = 0.0;  // m, >= 0: valid ranges are rounded to a multiple of it; 0: off
  double dropout_probability = 0.0;  // in [0, 1]: chance that a valid return is lost (+Inf)
  // The radiometric range limit (detected()), off while detection_range is 0: a datasheet's
  // "range R at reflectivity rho", a Lambertian target of reflectivity detection_reflectivity
  // seen head-on being detected up to detection_range and no farther.
  double detection_range = 0.0;        // m, >= 0; 0: every hit is detected
  double detection_reflectivity = 0.1;  // > 0

  // Whether the measurement needs each hit's reflectance and incidence.
  bool needsIncidence() const { return intensity || detection_range > 0; }
  // No bias, noise, quantization, dropout or detection limit: a measured range is the cast's.
  bool isIdeal() const {
    return range_bias == 0 && noise_stddev == 0 && range_resolution == 0 &&
           dropout_probability == 0 && detection_range == 0;
  }

  // Throws std::invalid_argument naming the field and its value.
  void validate() const;
};

// REP 117 for one noise-free range from the caster: a hit in [range_min, range_max] is itself, a
// hit closer than range_min follows the policy, no hit is +Inf, NaN stays NaN. Under pass_through
// the cast starts at range_min (ScanSpec::castConfig), so no closer range comes from it; one passed
// anyway is +Inf.
double classifyRange(double range, const MeasurementConfig& config);

// A valid range rounded to the nearest multiple of range_resolution (halves away from zero), as a
// driver reporting in fixed units does, then clamped to [range_min, range_max] so that a valid
// return stays valid (a multiple just outside a limit becomes the limit itself). Returns range
// unchanged if range_resolution is 0.
double quantizeRange(double range, const MeasurementConfig& config);

struct MeasuredScan {
  std::vector<float> ranges;       // REP 117
  std::vector<float> intensities;  // one per beam when MeasurementConfig::intensity, else empty
  std::vector<int> labels;         // label index of the body hit (also when too close), -1 for none
};

// Whether a return of reflectance rho at range r (m) and incidence cos_incidence is strong enough
// to be detected: the received power of a Lambertian target filling the beam goes as
// rho cos(theta) / r^2 (no atmosphere, no specular part, no near-field or saturation effects, no
// dependence on the beam's footprint), and the threshold is that of the datasheet's target:
// detection_reflectivity / detection_range^2. True when detection_range is 0.
bool detected(double rho, double cos_incidence, double r, const MeasurementConfig& config);

// Each beam's range is classified (classifyRange, on the noise-free range, so validity follows the
// geometry); a valid one that is not detected() (on its noise-free range) reports no return: +Inf,
// label -1, intensity 0, and draws nothing. A valid and detected one then becomes
//   r = quantizeRange(clamp(range + range_bias + noise_stddev * N(0, 1), range_min, range_max))
// and is lost with probability dropout_probability; it is rounded once to float. Bias, noise and
// quantisation never make a valid return invalid; invalid returns (+-Inf, NaN) get none of them.
// A lost return reports what a real lidar reports for a beam without echo: +Inf (REP 117's "no
// return"), label -1 and intensity 0.
//
// Random draws: two generators, both mt19937_64, one for the noise seeded with noise_seed and one
// for the dropout seeded with noise_seed ^ kDropoutSeedMix. Beams are visited in index order; each
// valid beam draws one N(0, 1) from the first if noise_stddev > 0 (even if it is then lost) and
// one uniform u in [0, 1) from the second if dropout_probability > 0, lost iff u <
// dropout_probability. So a seed fixes both sequences, and changing the dropout probability does
// not change the noise of the beams that remain. Both sequences continue across calls.
class MeasurementModel {
 public:
  static constexpr std::uint64_t kDropoutSeedMix = 0x9E3779B97F4A7C15ULL;

  explicit MeasurementModel(const MeasurementConfig& config);  // validates

  // A new configuration for the next measure() (e.g. from dynamic_reconfigure): validates it, and
  // restarts both random sequences if noise_seed changed; otherwise they continue.
  void setConfig(const MeasurementConfig& config);

  // reflectivity is indexed by label (missing entries count as 1); intensity needs
  // result.cos_incidence. With surface (sampleSurfaces, same scan), a beam's reflectance is the
  // surface's where it gives one (else the label's), and its incidence is the surface's.
  void measure(const Scene& scene, const ScanResult& result, const std::vector<double>& reflectivity,
               MeasuredScan* out, const SurfaceSamples* surface = nullptr);

 private:
  void seed(std::uint64_t seed);
  // The realism steps for one valid range (the class comment's formula and draws); false if lost.
  bool degrade(double* range);

  MeasurementConfig config_;
  std::mt19937_64 rng_;          // noise
  std::mt19937_64 dropout_rng_;  // dropout
  std::normal_distribution<double> noise_;
};

}  // namespace core
}  // namespace laser_raycast
