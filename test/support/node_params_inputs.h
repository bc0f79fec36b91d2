// Building the node's parameters in unit tests: values as the parameter server returns a namespace,
// parsed as the node parses them (no parameter server, no roscore).
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "expect_invalid.h"
#include "laser_raycast/node/node_params.h"

namespace laser_raycast_test {

// A struct of parameters, as the parameter server returns a namespace.
inline XmlRpc::XmlRpcValue values(
    const std::vector<std::pair<std::string, XmlRpc::XmlRpcValue>>& entries) {
  XmlRpc::XmlRpcValue v;
  v.begin();  // makes v an empty struct even without entries
  for (const auto& [name, value] : entries) v[name] = value;
  return v;
}

inline XmlRpc::XmlRpcValue list(const std::vector<XmlRpc::XmlRpcValue>& entries) {
  XmlRpc::XmlRpcValue v;
  v.setSize(static_cast<int>(entries.size()));
  for (std::size_t i = 0; i < entries.size(); ++i) v[static_cast<int>(i)] = entries[i];
  return v;
}

struct Parsed {
  laser_raycast::NodeParams params;
  laser_raycast::ParamReport report;
  std::string error;
};

// Parsed for a node whose topics are in namespace ns (the root namespace unless given).
inline Parsed parse(const XmlRpc::XmlRpcValue& v, const std::string& ns = "/") {
  Parsed out;
  out.error = laser_raycast::parseNodeParams(v, ns, &out.params, &out.report);
  return out;
}

// The parameters must be refused with a message containing every one of `mentions`.
inline void expectRefused(const XmlRpc::XmlRpcValue& v, const std::vector<std::string>& mentions,
                          const std::string& ns = "/") {
  const Parsed parsed = parse(v, ns);
  EXPECT_FALSE(parsed.error.empty()) << "accepted " << v.toXml() << " in namespace " << ns;
  expectMentions(parsed.error, mentions);
}

inline void expectAccepted(const XmlRpc::XmlRpcValue& v, const std::string& ns = "/") {
  const Parsed parsed = parse(v, ns);
  EXPECT_EQ(parsed.error, "") << v.toXml() << " in namespace " << ns;
}

}  // namespace laser_raycast_test
