// URDF text into a urdfdom model, together with what urdfdom only logs. Private to the loader
// library.
#pragma once

#include <urdf_model/model.h>
#include <urdf_world/types.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace laser_raycast {

// The <visual> or <collision> elements urdfdom dropped: (link, "visual"/"collision") -> reasons.
using DroppedElements = std::map<std::pair<std::string, std::string>, std::vector<std::string>>;

// The model urdfdom parses from xml. urdfdom drops a <visual> or <collision> it cannot parse (a
// "nan" size, an empty <geometry>) without failing: those go into *dropped with urdfdom's reasons.
// Throws SceneLoadError, starting with source, with urdfdom's reasons when it cannot parse the
// URDF at all.
urdf::ModelInterfaceSharedPtr parseUrdf(const std::string& xml, const std::string& source,
                                        DroppedElements* dropped);

}  // namespace laser_raycast
