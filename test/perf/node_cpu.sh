#!/bin/bash
# The node's CPU with `sweep: rotating` against `instant`, sensor by sensor, on the warehouse drive
# of make_warehouse_bag.py (README, "Rotating scanners"): a roscore of its own, the bag played with
# --clock (use_sim_time), one node a run with the sensor's preset on `velodyne`, and a subscriber
# (rostopic hz) so that the node casts. Prints, for each preset and sweep, the node's CPU (user and
# system) over the played seconds, as a percentage of one core, and the rate rostopic hz saw.
#
#   test/perf/node_cpu.sh DIR [SECONDS [PRESET ...]]
#
# DIR: what make_warehouse_bag.py wrote; SECONDS: of the drive to play (default 20); PRESET:
# sensor_model values (default LDS-01 UTM-30LX VLP-16 OS1-64). ROS_PORT (default 11399): the
# roscore's port. Needs the workspace's setup.bash sourced.
set -eu
DIR=$(cd "$1" && pwd)
SECONDS_PLAYED=${2:-20}
shift $(($# < 2 ? $# : 2))
PRESETS=("$@")
[ ${#PRESETS[@]} -gt 0 ] || PRESETS=(LDS-01 UTM-30LX VLP-16 OS1-64)
export PATH=/usr/bin:$PATH
export ROS_MASTER_URI=http://localhost:${ROS_PORT:-11399}
WORK=$(mktemp -d)
roscore -p "${ROS_PORT:-11399}" >"$WORK/roscore.log" 2>&1 &
CORE=$!
trap 'kill $CORE 2>/dev/null; wait $CORE 2>/dev/null; rm -rf "$WORK"' EXIT
for _ in $(seq 50); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done
rosparam set /use_sim_time true
cpu() { awk '{print ($14 + $15) / 100}' "/proc/$1/stat"; }  # user + system, s
printf "%-10s %-9s %8s %10s\n" preset sweep "cpu_%" rate_hz
for preset in "${PRESETS[@]}"; do
  for sweep in rotating instant; do
    cat >"$WORK/params.yaml" <<EOF
fixed_frame: map
models: [{file: $DIR/warehouse.urdf}]
sensors:
  - {name: s, frame_id: velodyne, topic: out, sensor_model: $preset, sweep: $sweep}
EOF
    rosparam delete /node_cpu >/dev/null 2>&1 || true
    rosparam load "$WORK/params.yaml" /node_cpu
    rosrun laser_raycast laser_raycast_node __name:=node_cpu >"$WORK/node.log" 2>&1 &
    NODE=$!
    # Started (the scene loaded) when it says so.
    for _ in $(seq 100); do grep -q "laser_raycast: started" "$WORK/node.log" && break; sleep 0.1; done
    rostopic hz /out >"$WORK/hz.log" 2>&1 &
    HZ=$!
    sleep 1
    before=$(cpu $NODE)
    # -d 1: the node's TF listener connects before /tf_static (not latched in the bag) is played.
    rosbag play -q --clock -d 1 -u "$SECONDS_PLAYED" "$DIR/drive.bag" >/dev/null 2>&1
    after=$(cpu $NODE)
    kill -INT $HZ $NODE
    wait $HZ $NODE 2>/dev/null || true
    rate=$(grep "average rate" "$WORK/hz.log" | tail -1 | awk '{print $3}')
    awk -v p="$preset" -v s="$sweep" -v a="$after" -v b="$before" -v t="$SECONDS_PLAYED" \
      -v r="${rate:-none}" 'BEGIN { printf "%-10s %-9s %8.2f %10s\n", p, s, 100 * (a - b) / (t + 1), r }' 
  done
done
