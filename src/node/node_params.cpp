#include "laser_raycast/node/node_params.h"

#include <ros/console.h>
#include <ros/param.h>

#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <type_traits>

namespace laser_raycast {
namespace {

const char* typeName(XmlRpc::XmlRpcValue::Type type) {
  switch (type) {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return "bool";
    case XmlRpc::XmlRpcValue::TypeInt:
      return "int";
    case XmlRpc::XmlRpcValue::TypeDouble:
      return "double";
    case XmlRpc::XmlRpcValue::TypeString:
      return "string";
    case XmlRpc::XmlRpcValue::TypeArray:
      return "list";
    case XmlRpc::XmlRpcValue::TypeStruct:
      return "dict";
    default:
      return "other";
  }
}

// Reads private parameters with type checks, logs each once, and keeps the first error. A parameter
// of the wrong type is an error rather than a silent fall back to the default.
class ParamReader {
 public:
  explicit ParamReader(const ros::NodeHandle& pnh) : pnh_(pnh) {}

  bool has(const std::string& name) {
    read_.insert(name);
    return pnh_.hasParam(name);
  }

  double number(const std::string& name, double fallback, const char* unit) {
    return scalar<double>(name, fallback, unit, "a number",
                          [](XmlRpc::XmlRpcValue& v, double* out) {
                            if (v.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
                              *out = static_cast<double>(v);
                            } else if (v.getType() == XmlRpc::XmlRpcValue::TypeInt) {
                              *out = static_cast<int>(v);
                            } else {
                              return false;
                            }
                            return true;
                          });
  }

  int integer(const std::string& name, int fallback, const char* unit) {
    return scalar<int>(name, fallback, unit, "an integer", [](XmlRpc::XmlRpcValue& v, int* out) {
      if (v.getType() != XmlRpc::XmlRpcValue::TypeInt) return false;
      *out = static_cast<int>(v);
      return true;
    });
  }

  bool boolean(const std::string& name, bool fallback) {
    return scalar<bool>(name, fallback, "", "true or false", [](XmlRpc::XmlRpcValue& v, bool* out) {
      if (v.getType() != XmlRpc::XmlRpcValue::TypeBoolean) return false;
      *out = static_cast<bool>(v);
      return true;
    });
  }

  std::string text(const std::string& name, const std::string& fallback) {
    return scalar<std::string>(name, fallback, "", "a string",
                               [](XmlRpc::XmlRpcValue& v, std::string* out) {
                                 if (v.getType() != XmlRpc::XmlRpcValue::TypeString) return false;
                                 *out = static_cast<std::string>(v);
                                 return true;
                               });
  }

  std::vector<std::string> textList(const std::string& name) {
    XmlRpc::XmlRpcValue v;
    std::vector<std::string> value;
    if (get(name, &v)) {
      if (v.getType() != XmlRpc::XmlRpcValue::TypeArray) {
        wrongType(name, v, "a list of strings");
      } else {
        for (int i = 0; i < v.size(); ++i) {
          if (v[i].getType() != XmlRpc::XmlRpcValue::TypeString) {
            fail(name, "entry " + std::to_string(i) + " is a " + typeName(v[i].getType()) +
                           ", expected a string");
            break;
          }
          value.push_back(static_cast<std::string>(v[i]));
        }
      }
    }
    std::ostringstream s;
    for (std::size_t i = 0; i < value.size(); ++i) s << (i ? ", " : "") << value[i];
    ROS_INFO_STREAM("~" << name << " = [" << s.str() << "]");
    return value;
  }

  // The raw value (for structured parameters); false if unset.
  bool get(const std::string& name, XmlRpc::XmlRpcValue* v) {
    read_.insert(name);
    return pnh_.getParam(name, *v);
  }

  // A scalar parameter: the fallback if unset, an error if convert() refuses its type; logged once.
  template <typename T, class Convert>
  T scalar(const std::string& name, const T& fallback, const char* unit, const char* expected,
           Convert convert) {
    XmlRpc::XmlRpcValue v;
    T value = fallback;
    if (get(name, &v) && !convert(v, &value)) wrongType(name, v, expected);
    std::ostringstream shown;
    if constexpr (std::is_same_v<T, bool>) {
      shown << (value ? "true" : "false");
    } else if constexpr (std::is_same_v<T, std::string>) {
      shown << "'" << value << "'";
    } else {
      shown << value << (*unit ? " " : "") << unit;
    }
    ROS_INFO_STREAM("~" << name << " = " << shown.str());
    return value;
  }

  void fail(const std::string& name, const std::string& message) {
    failWith("parameter ~" + name + ": " + message);
  }
  // For messages that already name the parameter (the core's validate() names its fields, which
  // share the parameters' names).
  void failWith(const std::string& message) {
    if (error_.empty()) error_ = message;
  }
  void wrongType(const std::string& name, XmlRpc::XmlRpcValue& v, const char* expected) {
    std::ostringstream msg;
    msg << "is a " << typeName(v.getType()) << " (" << v.toXml() << "), expected " << expected;
    fail(name, msg.str());
  }

  const std::string& error() const { return error_; }

  // Private parameters that exist but were never read (typos such as ~angle_incremnt).
  std::vector<std::string> unknown() const {
    std::vector<std::string> names, unknown;
    ros::param::getParamNames(names);
    const std::string prefix = pnh_.getNamespace() + "/";
    for (const std::string& full : names) {
      if (full.compare(0, prefix.size(), prefix) != 0) continue;
      const std::string name = full.substr(prefix.size());
      const std::string top = name.substr(0, name.find('/'));
      if (!read_.count(top)) unknown.push_back(top);
    }
    return unknown;
  }

 private:
  ros::NodeHandle pnh_;
  std::set<std::string> read_;
  std::string error_;
};

bool readModels(ParamReader* reader, std::vector<ModelSource>* models) {
  XmlRpc::XmlRpcValue v;
  if (!reader->get("models", &v)) {
    models->push_back(ModelSource{"robot_description", "", ""});
    ROS_INFO("~models unset: the URDF in parameter robot_description");
    return true;
  }
  if (v.getType() != XmlRpc::XmlRpcValue::TypeArray || v.size() == 0) {
    reader->wrongType("models", v, "a non-empty list of {param: NAME} or {file: PATH} entries");
    return false;
  }
  for (int i = 0; i < v.size(); ++i) {
    const std::string where = "models[" + std::to_string(i) + "]";
    ModelSource m;
    XmlRpc::XmlRpcValue& e = v[i];
    if (e.getType() == XmlRpc::XmlRpcValue::TypeString) {
      m.param = static_cast<std::string>(e);
    } else if (e.getType() == XmlRpc::XmlRpcValue::TypeStruct) {
      for (auto it = e.begin(); it != e.end(); ++it) {
        if (it->second.getType() != XmlRpc::XmlRpcValue::TypeString) {
          reader->fail(where, "'" + it->first + "' must be a string");
          return false;
        }
        const std::string value = static_cast<std::string>(it->second);
        if (it->first == "param") {
          m.param = value;
        } else if (it->first == "file") {
          m.file = value;
        } else if (it->first == "tf_prefix") {
          m.tf_prefix = value;
        } else {
          reader->fail(where, "unknown key '" + it->first + "' (expected param, file, tf_prefix)");
          return false;
        }
      }
    } else {
      reader->wrongType(where, e, "a parameter name or a dict {param|file, tf_prefix}");
      return false;
    }
    if (m.param.empty() == m.file.empty()) {
      reader->fail(where, "give exactly one of 'param' and 'file'");
      return false;
    }
    ROS_INFO_STREAM("~" << where << " = " << m.describe()
                        << (m.tf_prefix.empty() ? "" : ", tf_prefix '" + m.tf_prefix + "'"));
    models->push_back(m);
  }
  return true;
}

bool readReflectivity(ParamReader* reader, std::map<std::string, double>* reflectivity) {
  XmlRpc::XmlRpcValue v;
  if (!reader->get("reflectivity", &v)) return true;
  if (v.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    reader->wrongType("reflectivity", v, "a dict {link: value}");
    return false;
  }
  for (auto it = v.begin(); it != v.end(); ++it) {
    double value;
    if (it->second.getType() == XmlRpc::XmlRpcValue::TypeDouble) {
      value = static_cast<double>(it->second);
    } else if (it->second.getType() == XmlRpc::XmlRpcValue::TypeInt) {
      value = static_cast<int>(it->second);
    } else {
      reader->wrongType("reflectivity/" + it->first, it->second, "a number");
      return false;
    }
    if (!(std::isfinite(value) && value >= 0)) {
      reader->fail("reflectivity/" + it->first,
                   "must be finite and >= 0, got " + std::to_string(value));
      return false;
    }
    ROS_INFO_STREAM("~reflectivity/" << it->first << " = " << value);
    (*reflectivity)[it->first] = value;
  }
  return true;
}

}  // namespace

std::string ModelSource::describe() const {
  return param.empty() ? "file " + file : "parameter " + param;
}

bool readNodeParams(const ros::NodeHandle& pnh, NodeParams* p, std::string* error) {
  ParamReader r(pnh);
  p->frame_id = r.text("frame_id", p->frame_id);
  p->fixed_frame = r.text("fixed_frame", p->fixed_frame);
  for (const auto& [name, frame] :
       {std::pair<const char*, const std::string&>{"frame_id", p->frame_id},
        {"fixed_frame", p->fixed_frame}}) {
    if (frame.empty()) r.fail(name, "must not be empty");
    if (!frame.empty() && frame[0] == '/')
      r.fail(name, "'" + frame + "': tf2 frame ids must not start with '/'");
  }

  p->scan.fan.angle_min = r.number("angle_min", -M_PI, "rad");
  p->scan.fan.angle_max = r.number("angle_max", M_PI, "rad");
  const bool has_increment = r.has("angle_increment"), has_samples = r.has("samples");
  p->scan.fan.angle_increment = has_increment ? r.number("angle_increment", 0.0, "rad") : 0.0;
  p->scan.fan.samples = has_samples || !has_increment ? r.integer("samples", 360, "beams") : 0;
  if (has_increment && has_samples) r.fail("samples", "set ~angle_increment or ~samples, not both");

  p->scan.output.range_min = r.number("range_min", 0.0, "m");
  p->scan.output.range_max = r.number("range_max", 30.0, "m");
  const std::string policy = r.text("min_range_policy", "-inf");
  if (!core::parseMinRangePolicy(policy, &p->scan.output.min_range_policy)) {
    r.fail("min_range_policy", core::kMinRangePolicyNames.notOneOf(policy));
  }
  p->scan.output.noise_stddev = r.number("noise_stddev", 0.0, "m");
  const int seed = r.integer("noise_seed", 0, "");
  if (seed < 0) r.fail("noise_seed", "must be >= 0, got " + std::to_string(seed));
  p->scan.output.noise_seed = static_cast<std::uint64_t>(std::max(seed, 0));
  const std::string intensity = r.text("intensity", "off");
  if (intensity != "off" && intensity != "reflectivity") {
    r.fail("intensity", "'" + intensity + "' is not one of off, reflectivity");
  }
  p->scan.output.intensity = intensity == "reflectivity";
  readReflectivity(&r, &p->reflectivity);
  p->default_reflectivity = r.number("default_reflectivity", 1.0, "");
  if (!(std::isfinite(p->default_reflectivity) && p->default_reflectivity >= 0)) {
    r.fail("default_reflectivity", "must be finite and >= 0");
  }

  p->rate = r.number("rate", 10.0, "Hz");
  if (!(std::isfinite(p->rate) && p->rate > 0 && p->rate <= 1000)) {
    r.fail("rate", "must be in (0, 1000] Hz, got " + std::to_string(p->rate));
  }
  p->tf_timeout = r.number("tf_timeout", 0.1, "s");
  if (!(std::isfinite(p->tf_timeout) && p->tf_timeout >= 0 && p->tf_timeout <= 10)) {
    r.fail("tf_timeout", "must be in [0, 10] s, got " + std::to_string(p->tf_timeout));
  }

  const std::string geometry = r.text("geometry", "visual");
  if (!parseGeometrySource(geometry, &p->geometry)) {
    r.fail("geometry", kGeometrySourceNames.notOneOf(geometry));
  }
  p->skip_bad_geometry = r.boolean("skip_bad_geometry", false);
  readModels(&r, &p->models);
  p->ignore_links = r.textList("ignore_links");

  const std::string method = r.text("method", "watertight");
  if (!core::parseTriangleMethod(method, &p->scan.method)) {
    r.fail("method", core::kTriangleMethodNames.notOneOf(method));
  }
  p->scan.cull_backfaces = r.boolean("cull_backfaces", false);

  p->pose_topic = r.text("pose_topic", "");
  p->pose_frame = r.text("pose_frame", "");
  if (!p->pose_frame.empty() && p->pose_topic.empty()) {
    r.fail("pose_frame", "is set to '" + p->pose_frame + "' but ~pose_topic is not");
  }
  if (!p->pose_frame.empty() && p->pose_frame[0] == '/') {
    r.fail("pose_frame", "'" + p->pose_frame + "': tf2 frame ids must not start with '/'");
  }

  // Ranges, angles and noise through the core's own validation, which names the field.
  if (r.error().empty()) {
    try {
      p->scan.validate();
    } catch (const std::invalid_argument& e) {
      r.failWith(std::string("bad parameter: ") + e.what());
    }
  }

  for (const std::string& name : r.unknown()) {
    ROS_WARN_STREAM("~" << name << " is not a parameter of this node (ignored; a typo?)");
  }
  *error = r.error();
  return error->empty();
}

}  // namespace laser_raycast
