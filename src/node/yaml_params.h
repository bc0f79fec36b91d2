// Parameters from a YAML file, as `rosparam load` sets them and a node then reads them from the
// parameter server (XmlRpc): mappings become structs, sequences arrays, and plain scalars take the
// type PyYAML's YAML 1.1 rules (which rosparam uses) give them: true/false/yes/no/on/off in any of
// their three spellings are booleans; decimal, 0x, octal (a leading 0) and 0b integers, with '_'
// separators and base-60 forms, are ints; numbers with a '.' (the exponent signed), .inf and .nan
// are doubles; anything else is a string. A quoted scalar or one tagged !!str is a string. So one
// file configures the node (<rosparam file=... command="load"/>) and simulate_bag alike.
#pragma once

#include <xmlrpcpp/XmlRpcValue.h>

#include <stdexcept>
#include <string>

namespace laser_raycast {

// A file that is not YAML or holds what the parameter server cannot: the message names the file,
// the line and column (from 1) and the key.
class YamlParamsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The parameters of a YAML text; `source` names it in messages. The top level must be a mapping
// (a namespace of parameters). Throws YamlParamsError for a syntax error, a null value (the
// parameter server holds none), an int beyond 32 bits (XmlRpc's), a non-scalar key, or a tag
// other than !!str, !!int, !!float, !!bool, !!seq and !!map.
XmlRpc::XmlRpcValue parseYamlParams(const std::string& text, const std::string& source);

// The same from a file; also throws YamlParamsError if it cannot be read.
XmlRpc::XmlRpcValue loadYamlParams(const std::string& path);

}  // namespace laser_raycast
