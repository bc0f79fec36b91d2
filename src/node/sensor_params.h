// Reading one sensor's parameters (SensorParams) with a ParamReader: the same functions read the
// private namespace (the one-sensor shorthand) and each entry of ~sensors.
#pragma once

#include <string>
#include <vector>

#include "laser_raycast/node/node_params.h"
#include "param_reader.h"

namespace laser_raycast {

// tf2 frame ids have no leading '/' (tf1 had one); an empty one names no frame (an error unless
// optional).
void checkFrame(ParamReader* r, const std::string& name, const std::string& frame, bool optional);

// A topic name the node can subscribe or advertise with its NodeHandle: valid, and not private
// ('~': a NodeHandle refuses those; a global or relative name is resolved in the node's namespace).
// `name` is the parameter, relative to r's prefix. False (after r->fail) if it is not.
bool checkTopic(ParamReader* r, const std::string& name, const std::string& topic);

// Every sensor parameter, in the order the log lists them, into *s, whose values are the
// fallbacks (the defaults, or for an entry of ~sensors the private namespace's sensor). An entry
// (`entry`) also has a name and a topic, and must give its frame_id. Settings without effect go to
// *warnings.
void readSensor(ParamReader* r, SensorParams* s, bool entry, std::vector<std::string>* warnings);

}  // namespace laser_raycast
