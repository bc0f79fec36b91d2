// Reading one sensor's parameters (SensorParams) with a ParamReader: the same functions read the
// private namespace (the one-sensor shorthand) and each entry of ~sensors.
#pragma once

#include <string>

#include "laser_raycast/node/node_params.h"
#include "param_reader.h"

namespace laser_raycast {

// tf2 frame ids have no leading '/' (tf1 had one); an empty one names no frame (an error unless
// optional).
void checkFrame(ParamReader* r, const std::string& name, const std::string& frame, bool optional);

// Every sensor parameter, in the order the log lists them, into *s (which holds the defaults).
void readSensor(ParamReader* r, SensorParams* s);

// The names readSensor reads, in order.
std::vector<std::string> sensorParamNames();

}  // namespace laser_raycast
