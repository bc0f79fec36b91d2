#include "laser_raycast/node/node_params.h"

#include <ros/console.h>
#include <ros/names.h>
#include <ros/node_handle.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "laser_raycast/core/caster.h"
#include "param_reader.h"
#include "sensor_params.h"

// The parameters are read in groups: the node's own here, each sensor's in sensor_params.cpp.
namespace laser_raycast {
namespace {

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
void readReflectivityDict(ParamReader* r, std::map<std::string, double>* reflectivity) {
  const char* expected = "a dict {link: reflectivity}";
  const XmlRpc::XmlRpcValue* v = r->container("reflectivity", expected);
  if (v && v->getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    r->wrongType("reflectivity", *v, expected);
  } else if (v) {
    readReflectivityEntries(r, "", *v, reflectivity);
  }
  std::string shown;
  for (const auto& [link, value] : *reflectivity) {
    shown += (shown.empty() ? "" : ", ") + link + ": " + formatNumber(value);
  }
  r->note(r->prefix() + "reflectivity = {" + shown + "}");
}

// The geometry's reflectivity, for the sensors whose ~intensity is on.
void readReflectivity(ParamReader* r, NodeParams* p) {
  readReflectivityDict(r, &p->reflectivity);
  p->default_reflectivity = r->number("default_reflectivity", p->default_reflectivity, "");
  if (!(std::isfinite(p->default_reflectivity) && p->default_reflectivity >= 0)) {
    r->fail("default_reflectivity",
            "must be finite and >= 0, got " + formatNumber(p->default_reflectivity));
  }
}

void readTfTimeout(ParamReader* r, NodeParams* p) {
  p->tf_timeout = r->number("tf_timeout", p->tf_timeout, "s");
  if (!(std::isfinite(p->tf_timeout) && p->tf_timeout >= 0 &&
        p->tf_timeout <= NodeParams::kMaxTfTimeout)) {
    r->fail("tf_timeout", "must be in [0, " + formatNumber(NodeParams::kMaxTfTimeout) +
                              "] s, got " + formatNumber(p->tf_timeout));
  }
}

// ~threads: core::CastConfig::validate() holds the bounds, and its message names the value.
void readThreads(ParamReader* r, NodeParams* p) {
  p->threads = r->integer("threads", p->threads, "");
  core::CastConfig config;
  config.threads = p->threads;
  try {
    config.validate();
  } catch (const std::invalid_argument& e) {
    r->fail("threads", e.what());
  }
}

// The keys of a ~models entry: the one that says what it is, and what each kind may add.
const char* const kModelKeys = "param, file, tf_prefix, map, map_topic, height, frame, name";

// Whether key may be given in an entry of this kind (the kind's own key).
bool keyFitsKind(const std::string& key, const std::string& kind) {
  if (key == "tf_prefix") return kind == "param" || kind == "file";
  if (key == "height") return kind == "map" || kind == "map_topic";
  if (key == "frame") return kind == "map";
  if (key == "name") return kind != "map_topic";
  return key == kind;
}

// A dict entry's values into m; false (after r->fail) for an unknown key or a wrong type.
bool readModelKeys(ParamReader* r, const std::string& where, const XmlRpc::XmlRpcValue& e,
                   ModelSource* m) {
  for (auto it = e.begin(); it != e.end(); ++it) {
    const std::string& key = it->first;
    const XmlRpc::XmlRpcValue& value = it->second;
    const auto type = value.getType();
    if (key == "height") {
      if (type != XmlRpc::XmlRpcValue::TypeDouble && type != XmlRpc::XmlRpcValue::TypeInt) {
        r->wrongType(where + "/height", value, "a number (m)");
        return false;
      }
      m->height = type == XmlRpc::XmlRpcValue::TypeInt ? static_cast<const int&>(value)
                                                       : static_cast<const double&>(value);
      continue;
    }
    std::string* field = key == "param"       ? &m->param
                         : key == "file"      ? &m->file
                         : key == "tf_prefix" ? &m->tf_prefix
                         : key == "map"       ? &m->map
                         : key == "map_topic" ? &m->map_topic
                         : key == "frame"     ? &m->frame
                         : key == "name"      ? &m->name
                                              : nullptr;
    if (!field) {
      r->fail(where, "unknown key '" + key + "' (expected " + kModelKeys + ")");
      return false;
    }
    if (type != XmlRpc::XmlRpcValue::TypeString) {
      r->wrongType(where + "/" + key, value, "a string");
      return false;
    }
    *field = static_cast<const std::string&>(value);
  }
  return true;
}

// One entry of ~models: a parameter name, or a dict with exactly one of param, file, map and
// map_topic, and the keys its kind takes (tf_prefix for a URDF; height, and frame for a map file).
// False (after r->fail) if it is malformed.
bool readModel(ParamReader* r, const std::string& where, const XmlRpc::XmlRpcValue& e,
               ModelSource* m) {
  if (e.getType() == XmlRpc::XmlRpcValue::TypeString) {
    m->param = static_cast<const std::string&>(e);
  } else if (e.getType() == XmlRpc::XmlRpcValue::TypeStruct) {
    if (!readModelKeys(r, where, e, m)) return false;
  } else {
    r->wrongType(where, e, "a parameter name or a dict {param|file|map|map_topic, ...}");
    return false;
  }
  const std::pair<const char*, const std::string*> kinds[] = {
      {"param", &m->param}, {"file", &m->file}, {"map", &m->map}, {"map_topic", &m->map_topic}};
  std::string kind;
  int given = 0;
  for (const auto& [name, value] : kinds) {
    if (!value->empty()) kind = name, ++given;
  }
  if (given != 1) {
    r->fail(where,
            "give exactly one of 'param', 'file', 'map' and 'map_topic', got " + describeValue(e));
    return false;
  }
  if (e.getType() == XmlRpc::XmlRpcValue::TypeStruct) {
    for (auto it = e.begin(); it != e.end(); ++it) {
      if (!keyFitsKind(it->first, kind)) {
        r->fail(where, "'" + it->first + "' does not go with '" + kind + "' (" + kind +
                           " entries take " +
                           (kind == "map"         ? "height, frame and name"
                            : kind == "map_topic" ? "height; the grid gives the frame"
                                                  : "tf_prefix and name") +
                           ")");
        return false;
      }
    }
  }
  if (!m->tf_prefix.empty() && m->tf_prefix[0] == '/') {
    r->fail(where, "tf_prefix '" + m->tf_prefix + "': tf2 frame ids must not start with '/'");
    return false;
  }
  if (m->isMap() && !(std::isfinite(m->height) && m->height > 0)) {
    r->fail(where + "/height", "must be finite and > 0 m, got " + formatNumber(m->height));
    return false;
  }
  if (!m->map.empty()) checkFrame(r, where + "/frame", m->frame, false);
  if (!m->map_topic.empty()) return checkTopic(r, where + "/map_topic", m->map_topic);
  return r->error().empty();
}

void readModels(ParamReader* r, std::vector<ModelSource>* models) {
  const char* expected =
      "a non-empty list of {param: NAME}, {file: PATH}, {map: PATH} or {map_topic: TOPIC} entries";
  const XmlRpc::XmlRpcValue* v = r->container("models", expected);
  if (v && (v->getType() != XmlRpc::XmlRpcValue::TypeArray || v->size() == 0)) {
    r->wrongType("models", *v, expected);
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
    std::string extra = m.tf_prefix.empty() ? "" : ", tf_prefix '" + m.tf_prefix + "'";
    if (m.isMap()) extra = ", walls " + formatNumber(m.height) + " m high";
    if (!m.map.empty()) extra += " in frame '" + m.frame + "'";
    r->note(r->prefix() + "models[" + std::to_string(i) + "] = " + m.describe() + extra);
  }
}

// The bounds of one mesh file's import (0: from the file's size), checked by
// MeshImportBounds::validate() under the parameters' names.
void readMeshImportBounds(ParamReader* r, MeshImportBounds* b) {
  b->max_memory_mb = r->number("mesh_import_max_memory_mb", b->max_memory_mb, "MB (0: by size)");
  b->max_seconds = r->number("mesh_import_timeout", b->max_seconds, "s (0: by size)");
  const std::string name = "parameter " + r->prefix() + "mesh_import_";
  try {
    b->validate(name + "max_memory_mb:", name + "timeout:");
  } catch (const std::invalid_argument& e) {
    r->failWith(e.what());
  }
}

// Which geometry is cast against.
void readScene(ParamReader* r, NodeParams* p) {
  p->geometry = r->choice("geometry", p->geometry, kGeometrySourceNames);
  p->skip_bad_geometry = r->boolean("skip_bad_geometry", p->skip_bad_geometry);
  readMeshImportBounds(r, &p->mesh_import);
  readModels(r, &p->models);
  p->ignore_links = r->textList("ignore_links");
}

// The default name of an entry: its frame_id made a valid name without '/' (it names the namespace
// of the sensor's live parameters): every character other than a letter, a digit or '_' becomes
// '_', and "sensor_" goes in front if it does not start with a letter ("r1/laser": "r1_laser").
std::string defaultName(const std::string& frame_id) {
  std::string name = frame_id;
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  }
  if (name.empty() || !std::isalpha(static_cast<unsigned char>(name[0]))) name = "sensor_" + name;
  return name;
}

// The default topic of a sensor: relative to the node's namespace, under its name for an entry.
std::string defaultTopic(const SensorParams& s, bool entry) {
  const std::string type = s.planar() ? "scan" : "points";
  return entry ? s.name + "/" + type : type;
}

// Entry i of ~sensors, with `base` (the private namespace's sensor) as its defaults; false (after
// r->fail) if it is bad.
bool readSensorEntry(ParamReader* r, int i, const XmlRpc::XmlRpcValue& e, const SensorParams& base,
                     SensorParams* s, std::vector<std::string>* warnings) {
  const std::string where = "sensors[" + std::to_string(i) + "]";
  if (e.getType() != XmlRpc::XmlRpcValue::TypeStruct) {
    r->wrongType(where, e, "a dict of sensor parameters with at least frame_id");
    return false;
  }
  ParamReader er(e, r->prefix() + where + "/");
  *s = base;
  readSensor(&er, s, true, warnings);
  for (const std::string& line : er.log()) r->note(line);
  for (const std::string& name : er.unknown()) {
    warnings->push_back(er.prefix() + name + " is not a sensor parameter (ignored; a typo?)");
  }
  if (!er.error().empty()) {
    r->failWith(er.error());
    return false;
  }
  std::string why;
  if (s->name.empty()) {
    s->name = defaultName(s->frame_id);
    r->note(r->prefix() + where + "/name unset: '" + s->name + "' (from frame_id)");
  }
  if (!ros::names::validate(s->name, why) || s->name.find('/') != std::string::npos) {
    r->fail(where + "/name", "'" + s->name + "' is not a valid name without '/' (it names the " +
                                 "sensor's namespace): " + why);
    return false;
  }
  if (s->topic.empty()) s->topic = defaultTopic(*s, true);
  return checkTopic(r, where + "/topic", s->topic);
}

// Two sensors with one name or one topic (scans or labels) would mix their messages. Topics are
// compared as the node advertises them, resolved in its namespace `ns` ("scan" and "/scan" are one
// topic in the root namespace); remappings given to the node are not known here.
void checkDistinct(ParamReader* r, const std::vector<SensorParams>& sensors,
                   const std::string& ns) {
  // Each sensor's topics as given and as resolved.
  const auto topics = [&](const SensorParams& s) {
    std::vector<std::pair<std::string, std::string>> out;
    for (const std::string& topic : {s.topic, s.labelsTopic()}) {
      out.emplace_back(topic, ros::names::resolve(ns, topic, false));
    }
    return out;
  };
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const std::string here = "sensors[" + std::to_string(i) + "]";
      const std::string there = r->prefix() + "sensors[" + std::to_string(j) + "]";
      if (sensors[i].name == sensors[j].name) {
        r->fail(here + "/name", "'" + sensors[i].name + "' is also the name of " + there);
      }
      for (const auto& [given, resolved] : topics(sensors[i])) {
        for (const auto& [other, other_resolved] : topics(sensors[j])) {
          if (resolved != other_resolved) continue;
          r->fail(here + "/topic", "'" + given + "' publishes on " + resolved + " (in namespace " +
                                       ns + "), as " + there + " does ('" + other + "')");
        }
      }
    }
  }
}

// The sensors: the private namespace's sensor parameters describe one, or, with ~sensors, are the
// defaults of each entry.
void readSensors(ParamReader* r, const std::string& ns, NodeParams* p,
                 std::vector<std::string>* warnings) {
  SensorParams base;
  readSensor(r, &base, false, warnings);
  p->sensors.clear();
  const char* expected = "a non-empty list of dicts of sensor parameters";
  const XmlRpc::XmlRpcValue* v = r->container("sensors", expected);
  if (!v) {
    base.name = base.frame_id;
    base.topic = defaultTopic(base, false);
    p->sensors.push_back(base);
    r->note(r->prefix() + "sensors unset (one sensor: the parameters above)");
    return;
  }
  if (v->getType() != XmlRpc::XmlRpcValue::TypeArray || v->size() == 0) {
    r->wrongType("sensors", *v, expected);
    return;
  }
  for (int i = 0; i < v->size(); ++i) {
    SensorParams s;
    if (!readSensorEntry(r, i, (*v)[i], base, &s, warnings)) return;
    p->sensors.push_back(s);
  }
  checkDistinct(r, p->sensors, ns);
}

// Every group, in the order the log lists them: the node's own, then the sensors'.
void readAll(ParamReader* r, const std::string& ns, NodeParams* p,
             std::vector<std::string>* warnings) {
  p->fixed_frame = r->text("fixed_frame", p->fixed_frame);
  checkFrame(r, "fixed_frame", p->fixed_frame, false);
  readTfTimeout(r, p);
  readThreads(r, p);
  readScene(r, p);
  readReflectivity(r, p);
  readSensors(r, ns, p, warnings);
  const bool any_intensity =
      std::any_of(p->sensors.begin(), p->sensors.end(),
                  [](const SensorParams& s) { return s.scan.output.intensity; });
  if (!any_intensity && !p->reflectivity.empty()) {
    warnings->push_back(r->prefix() + "reflectivity is set but " + r->prefix() +
                        "intensity is off: no intensities are published");
  }
}

}  // namespace

double NodeParams::history() const {
  double longest_scan = 0;
  for (const SensorParams& s : sensors) longest_scan = std::max(longest_scan, 1.0 / s.rate);
  return tf_timeout + longest_scan + 1.0;
}

double NodeParams::tfCache() const { return std::max(10.0, history()); }

double NodeParams::poseHistory(const SensorParams& sensor) const {
  return history() + std::min(sensor.pose_timeout, kMaxTfTimeout);
}

std::string ModelSource::describe() const {
  if (!map.empty()) return "map " + map;
  if (!map_topic.empty()) return "map topic " + map_topic;
  return param.empty() ? "file " + file : "parameter " + param;
}

std::string parseNodeParams(const XmlRpc::XmlRpcValue& values, const std::string& ns, NodeParams* p,
                            ParamReport* report) {
  *p = NodeParams();
  *report = ParamReport();
  ParamReader r(values, "~");
  std::string why;
  if (!ros::names::validate(ns, why) || ns.empty() || ns[0] != '/') {
    // The caller's mistake, not the user's: the namespace comes from a NodeHandle.
    throw std::invalid_argument("parseNodeParams: namespace '" + ns + "' is not a global name");
  }
  readAll(&r, ns, p, &report->warnings);

  for (const std::string& name : r.unknown()) {
    // dynamic_reconfigure keeps an entry's live parameters under ~<its name>.
    const bool live = std::any_of(p->sensors.begin(), p->sensors.end(),
                                  [&](const SensorParams& s) { return s.name == name; });
    if (!live) {
      report->warnings.push_back(r.prefix() + name +
                                 " is not a parameter of this node (ignored; a typo?)");
    }
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
  readAll(&r, "/", &p, &warnings);
  return r.known();
}

bool readNodeParams(const ros::NodeHandle& nh, const ros::NodeHandle& pnh, NodeParams* params,
                    std::string* error) {
  // The whole private namespace in one struct (unset if nothing is set in it).
  XmlRpc::XmlRpcValue values;
  if (!pnh.getParam(pnh.getNamespace(), values)) values = XmlRpc::XmlRpcValue();
  // The namespace nh resolves relative names in. Not nh.getNamespace(): a nodelet's handle for the
  // root namespace has an empty one (roscpp then resolves in this node's namespace).
  const std::string ns = ros::names::parentNamespace(nh.resolveName("topic", false));
  ParamReport report;
  *error = parseNodeParams(values, ns, params, &report);
  for (const std::string& line : report.values) ROS_INFO_STREAM(line);
  for (const std::string& warning : report.warnings) ROS_WARN_STREAM(warning);
  return error->empty();
}

}  // namespace laser_raycast
