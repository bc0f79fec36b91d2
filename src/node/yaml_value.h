// A list or dict parameter given as a string of YAML, read as the list or dict it holds. roscpp
// sets `_elevations:="[-0.1, 0.1]"` from the command line as a string (it tries an int, a double
// and a bool, nothing else), and so does roslaunch for a <param> without a type; the node reads
// such a string as rosparam would have set the list.
#pragma once

#include <xmlrpcpp/XmlRpcValue.h>

#include <string>

namespace laser_raycast {

// Reads `text` as YAML. If it is a list or a dict, *value becomes that list or dict as the
// parameter server holds one (lists as arrays, dicts as structs with the keys as strings) and
// true is returned. Scalars are typed by YAML 1.2's core schema: true and false (also True, TRUE,
// False, FALSE) are bools, integers ([-+]?[0-9]+) ints, decimals (a point or an exponent) and
// .inf, -.inf, .nan doubles; anything else, and every quoted scalar or one tagged !!str, is a
// string. Returns false with *error empty if `text` is YAML but not a list or dict (a plain
// string); false with *error saying where and why if it is not YAML (with line and column) or
// holds what no parameter can: a null (~, null, an empty value), an integer beyond int32 (the
// parameter server's ints), a key that is not a scalar.
bool parseYamlContainer(const std::string& text, XmlRpc::XmlRpcValue* value, std::string* error);

}  // namespace laser_raycast
