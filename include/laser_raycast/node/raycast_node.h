// The ROS wrapper: parameters, the scene, TF, the sensors and their timers, and the cast thread.
// main() and the nodelet only construct it and call init().
//
// Timing: each sensor's timer only queues a scan (stamped on a grid of its period) and returns; the
// cast thread casts it once TF covers its last beam's time, waiting up to ~tf_timeout for late
// transforms and not at all for dead ones (docs: README, "Faults"). So late or missing TF never
// costs the timers their rate.
#pragma once

#include <ros/ros.h>

#include <memory>
#include <vector>

#include "laser_raycast/core/scene.h"
#include "laser_raycast/node/node_params.h"

namespace laser_raycast {

class CastThread;
class MapTopics;
class NodeDiagnostics;
class PoseSubscriber;
class SceneEditor;
class Sensor;
class SensorReconfigure;
class SharedScene;
class TfListener;

class RaycastNode {
 public:
  // TF publishers usually start with or after the node (robot_state_publisher, a driver, a
  // simulator), so for this long after a sensor's first scan attempt, until its first scan, scans
  // that lack a transform are skipped without a warning. ROS time, like the scan timers: under
  // use_sim_time it follows /clock, as the TF publishers do. Then missing transforms are warned
  // about.
  static constexpr double kTfGracePeriod = 5.0;  // s

  RaycastNode(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~RaycastNode();  // stops the timers and the map topics, then the cast thread

  // Reads and validates the parameters, loads the scene, and starts publishing. Returns false after
  // logging (ROS_FATAL) what is wrong: a bad parameter, a missing URDF, or bad geometry.
  bool init();

 private:
  void startTimer(int sensor);
  // The cast queue's capacity: enough scans to wait out tf_timeout at every sensor's rate.
  void updateCapacity();
  void onTick(int sensor, const ros::Time& expected);
  void onReport(const ros::TimerEvent& event);

  // Achieved rates are checked (and warned about when low), and diagnostics published, this often.
  static constexpr double kReportPeriod = 1.0;  // s

  ros::NodeHandle nh_, pnh_;
  NodeParams params_;
  // The scene cast, swapped whole when a service call or a map topic's grid changes it
  // (shared_scene.h, scene_editor.h).
  std::unique_ptr<SharedScene> scene_;
  std::unique_ptr<SceneEditor> editor_;  // ~spawn_model and the other editing services
  std::unique_ptr<MapTopics> map_topics_;
  std::unique_ptr<TfListener> tf_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
  // After the sensors: destroyed first, as they add to the sensors' pose topics.
  std::vector<std::unique_ptr<PoseSubscriber>> pose_subscribers_;
  std::unique_ptr<CastThread> cast_thread_;
  std::unique_ptr<NodeDiagnostics> diagnostics_;
  std::vector<std::unique_ptr<SensorReconfigure>> reconfigure_;
  // Per sensor: a one-shot timer that starts the periodic one on its period's grid, the periodic
  // timer, and the last scan time queued.
  std::vector<ros::Timer> align_timers_, timers_;
  std::vector<ros::Time> last_queued_;
  ros::Timer report_timer_;
};

}  // namespace laser_raycast
