#include "laser_raycast/node/node_params.h"

#include <ros/console.h>
#include <ros/names.h>
#include <ros/node_handle.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "param_reader.h"

// The parameters are read in groups. The sensor's own groups (frames, fan, output, timing, pose
// source) take a reader over one struct, so that a list of sensors could later be read entry by
// entry with the same functions.
namespace laser_raycast {
namespace {

// tf2 frame ids have no leading '/' (tf1 had one); an empty one names no frame.
void checkFrame(ParamReader* r, const std::string& name, const std::string& frame, bool optional) {
  if (frame.empty() && !optional) r->fail(name, "must not be empty");
  if (!frame.empty() && frame[0] == '/') {
    r->fail(name, "'" + frame + "': tf2 frame ids must not start with '/'");
  }
}

void readFrames(ParamReader* r, NodeParams* p) {
  p->frame_id = r->text("frame_id", p->frame_id);
  checkFrame(r, "frame_id", p->frame_id, false);
  p->fixed_frame = r->text("fixed_frame", p->fixed_frame);
  checkFrame(r, "fixed_frame", p->fixed_frame, false);
}

// The beam count comes from exactly one of ~angle_increment and ~samples (neither:
// kDefaultSamples); the core checks the angles and the beam count.
void readFan(ParamReader* r, core::FanSpec* fan) {
  fan->angle_min = r->number("angle_min", fan->angle_min, "rad");
  fan->angle_max = r->number("angle_max", fan->angle_max, "rad");
  const bool has_increment = r->has("angle_increment"), has_samples = r->has("samples");
  if (has_increment) {
    fan->angle_increment = r->number("angle_increment", 0.0, "rad");
    if (!(std::isfinite(fan->angle_increment) && fan->angle_increment > 0)) {
      r->fail("angle_increment",
              "must be finite and > 0 rad, got " + formatNumber(fan->angle_increment));
    }
  } else {
    r->note(r->prefix() + "angle_increment unset (beams from " + r->prefix() + "samples)");
  }
  if (has_samples || !has_increment) {
    fan->samples = r->integer("samples", NodeParams::kDefaultSamples, "beams");
    if (fan->samples < 2) r->fail("samples", "must be >= 2, got " + std::to_string(fan->samples));
  } else {
    r->note(r->prefix() + "samples unset (beams from " + r->prefix() + "angle_increment)");
  }
  if (has_increment && has_samples) {
    r->fail("samples", "set " + r->prefix() + "angle_increment or " + r->prefix() +
                           "samples, not both (got angle_increment " +
                           formatNumber(fan->angle_increment) + " and samples " +
                           std::to_string(fan->samples) + ")");
  }
}

// The entries of a reflectivity dict, `link` being the path to it. The parameter server splits
// names at '/', so a link with a TF prefix ("robot2/wall") arrives as a nested dict ({robot2:
// {wall: 0.5}}): nested keys are joined with '/' again.
void readReflectivityEntries(ParamReader* r, const std::string& link, const XmlRpc::XmlRpcValue& v,
                             std::map<std::string, double>* reflectivity) {
  for (auto it = v.begin(); it != v.end(); ++it) {
    const std::string name = link.empty() ? it->first : link + "/" + it->first;
    const auto type = it->second.getType();
    if (type == XmlRpc::XmlRpcValue::TypeStruct) {
      readReflectivityEntries(r, name, it->second, reflectivity);
      continue;
    }
    if (type != XmlRpc::XmlRpcValue::TypeDouble && type != XmlRpc::XmlRpcValue::TypeInt) {
      r->wrongType("reflectivity/" + name, it->second, "a number");
      continue;
    }
    const double value = type == XmlRpc::XmlRpcValue::TypeInt
                             ? static_cast<const int&>(it->second)
                             : static_cast<const double&>(it->second);
    if (!(std::isfinite(value) && value >= 0)) {
      r->fail("reflectivity/" + name, "must be finite and >= 0, got " + formatNumber(value));
    }
    (*reflectivity)[name] = value;
  }
}

// ~reflectivity: {link: value >= 0}; an empty dict is the same as none.
void readReflectivity(ParamReader* r, std::map<std::string, double>* reflectivity) {
  const XmlRpc::XmlRpcValue* v = r->get("reflectivity");
  if (v && v->getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    r->wrongType("reflectivity", *v, "a dict {link: reflectivity}");
  } else if (v) {
    readReflectivityEntries(r, "", *v, reflectivity);
  }
  std::string shown;
  for (const auto& [link, value] : *reflectivity) {
    shown += (shown.empty() ? "" : ", ") + link + ": " + formatNumber(value);
  }
  r->note(r->prefix() + "reflectivity = {" + shown + "}");
}

// What the sensor reports: range limits, min-range policy, noise, intensity.
void readOutput(ParamReader* r, NodeParams* p, std::vector<std::string>* warnings) {
  core::EncoderConfig& out = p->scan.output;
  out.range_min = r->number("range_min", out.range_min, "m");
  out.range_max = r->number("range_max", out.range_max, "m");
  out.min_range_policy =
      r->choice("min_range_policy", out.min_range_policy, core::kMinRangePolicyNames);
  out.noise_stddev = r->number("noise_stddev", out.noise_stddev, "m");
  const int seed = r->integer("noise_seed", static_cast<int>(out.noise_seed), "");
  if (seed < 0) r->fail("noise_seed", "must be >= 0, got " + std::to_string(seed));
  out.noise_seed = static_cast<std::uint64_t>(std::max(seed, 0));
  out.intensity = r->choice("intensity", out.intensity, kIntensityNames);
  readReflectivity(r, &p->reflectivity);
  p->default_reflectivity = r->number("default_reflectivity", p->default_reflectivity, "");
  if (!(std::isfinite(p->default_reflectivity) && p->default_reflectivity >= 0)) {
    r->fail("default_reflectivity",
            "must be finite and >= 0, got " + formatNumber(p->default_reflectivity));
  }
  if (!out.intensity && !p->reflectivity.empty()) {
    warnings->push_back(r->prefix() + "reflectivity is set but " + r->prefix() +
                        "intensity is off: no intensities are published");
  }
}

void readTiming(ParamReader* r, NodeParams* p) {
  p->rate = r->number("rate", p->rate, "Hz");
  if (!(std::isfinite(p->rate) && p->rate > 0 && p->rate <= NodeParams::kMaxRate)) {
    r->fail("rate", "must be in (0, " + formatNumber(NodeParams::kMaxRate) + "] Hz, got " +
                        formatNumber(p->rate));
  }
  p->tf_timeout = r->number("tf_timeout", p->tf_timeout, "s");
  if (!(std::isfinite(p->tf_timeout) && p->tf_timeout >= 0 &&
        p->tf_timeout <= NodeParams::kMaxTfTimeout)) {
    r->fail("tf_timeout", "must be in [0, " + formatNumber(NodeParams::kMaxTfTimeout) +
                              "] s, got " + formatNumber(p->tf_timeout));
  }
}

// One entry of ~models: a parameter name, or a dict with exactly one of param and file, and an
// optional tf_prefix. False (after r->fail) if it is malformed.
bool readModel(ParamReader* r, const std::string& where, const XmlRpc::XmlRpcValue& e,
               ModelSource* m) {
  if (e.getType() == XmlRpc::XmlRpcValue::TypeString) {
    m->param = static_cast<const std::string&>(e);
  } else if (e.getType() == XmlRpc::XmlRpcValue::TypeStruct) {
    for (auto it = e.begin(); it != e.end(); ++it) {
      if (it->second.getType() != XmlRpc::XmlRpcValue::TypeString) {
        r->wrongType(where + "/" + it->first, it->second, "a string");
        return false;
      }
      const std::string& value = it->second;
      if (it->first == "param") {
        m->param = value;
      } else if (it->first == "file") {
        m->file = value;
      } else if (it->first == "tf_prefix") {
        m->tf_prefix = value;
      } else {
        r->fail(where, "unknown key '" + it->first + "' (expected param, file, tf_prefix)");
        return false;
      }
    }
  } else {
    r->wrongType(where, e, "a parameter name or a dict {param|file, tf_prefix}");
    return false;
  }
  if (m->param.empty() == m->file.empty()) {
    r->fail(where, "give exactly one of 'param' and 'file', got " + describeValue(e));
    return false;
  }
  if (!m->tf_prefix.empty() && m->tf_prefix[0] == '/') {
    r->fail(where, "tf_prefix '" + m->tf_prefix + "': tf2 frame ids must not start with '/'");
    return false;
  }
  return true;
}

void readModels(ParamReader* r, std::vector<ModelSource>* models) {
  const XmlRpc::XmlRpcValue* v = r->get("models");
  if (v && (v->getType() != XmlRpc::XmlRpcValue::TypeArray || v->size() == 0)) {
    r->wrongType("models", *v, "a non-empty list of {param: NAME} or {file: PATH} entries");
  } else if (v) {
    models->clear();
    for (int i = 0; i < v->size(); ++i) {
      ModelSource m;
      if (!readModel(r, "models[" + std::to_string(i) + "]", (*v)[i], &m)) return;
      models->push_back(m);
    }
  }
  for (std::size_t i = 0; i < models->size(); ++i) {
    const ModelSource& m = (*models)[i];
    r->note(r->prefix() + "models[" + std::to_string(i) + "] = " + m.describe() +
            (m.tf_prefix.empty() ? "" : ", tf_prefix '" + m.tf_prefix + "'"));
  }
}

// Which geometry is cast against, and how.
void readScene(ParamReader* r, NodeParams* p) {
  p->geometry = r->choice("geometry", p->geometry, kGeometrySourceNames);
  p->skip_bad_geometry = r->boolean("skip_bad_geometry", p->skip_bad_geometry);
  readModels(r, &p->models);
  p->ignore_links = r->textList("ignore_links");
  p->scan.method = r->choice("method", p->scan.method, core::kTriangleMethodNames);
  p->scan.cull_backfaces = r->boolean("cull_backfaces", p->scan.cull_backfaces);
}

// Where the sensor pose comes from: TF, or a topic giving the pose of pose_frame.
void readPoseSource(ParamReader* r, NodeParams* p) {
  p->pose_topic = r->text("pose_topic", p->pose_topic);
  std::string why;
  if (!p->pose_topic.empty() && !ros::names::validate(p->pose_topic, why)) {
    r->fail("pose_topic", "'" + p->pose_topic + "' is not a valid topic name: " + why);
  }
  p->pose_frame = r->text("pose_frame", p->pose_frame);
  checkFrame(r, "pose_frame", p->pose_frame, true);
  if (!p->pose_frame.empty() && p->pose_topic.empty()) {
    r->fail("pose_frame", "is set to '" + p->pose_frame + "' but " + r->prefix() +
                              "pose_topic is not (pose_frame names the frame whose pose the "
                              "topic gives)");
  }
}

// Every group, in the order the log lists them.
void readAll(ParamReader* r, NodeParams* p, std::vector<std::string>* warnings) {
  readFrames(r, p);
  readFan(r, &p->scan.fan);
  readOutput(r, p, warnings);
  readTiming(r, p);
  readScene(r, p);
  readPoseSource(r, p);
}

}  // namespace

std::string ModelSource::describe() const {
  return param.empty() ? "file " + file : "parameter " + param;
}

std::string parseNodeParams(const XmlRpc::XmlRpcValue& values, NodeParams* p, ParamReport* report) {
  *p = NodeParams();
  *report = ParamReport();
  ParamReader r(values, "~");
  readAll(&r, p, &report->warnings);

  // The angles and beam count, ranges and noise through the core's own validation, which names
  // the field (the fields share the parameters' names).
  if (r.error().empty()) {
    try {
      p->scan.validate();
    } catch (const std::invalid_argument& e) {
      r.failWith(std::string("bad parameter: ") + e.what());
    }
  }
  for (const std::string& name : r.unknown()) {
    report->warnings.push_back(r.prefix() + name +
                               " is not a parameter of this node (ignored; a typo?)");
  }
  report->values = r.log();
  return r.error();
}

std::vector<std::string> nodeParamNames() {
  // Reading an empty namespace asks for every parameter.
  const XmlRpc::XmlRpcValue none;
  ParamReader r(none, "~");
  NodeParams p;
  std::vector<std::string> warnings;
  readAll(&r, &p, &warnings);
  return r.known();
}

bool readNodeParams(const ros::NodeHandle& pnh, NodeParams* params, std::string* error) {
  // The whole private namespace in one struct (unset if nothing is set in it).
  XmlRpc::XmlRpcValue values;
  if (!pnh.getParam(pnh.getNamespace(), values)) values = XmlRpc::XmlRpcValue();
  ParamReport report;
  *error = parseNodeParams(values, params, &report);
  for (const std::string& line : report.values) ROS_INFO_STREAM(line);
  for (const std::string& warning : report.warnings) ROS_WARN_STREAM(warning);
  return error->empty();
}

}  // namespace laser_raycast
