#!/usr/bin/env python3
"""A Locus CSV log (docs/log-format.md) written as a ROS 2 bag by the
`rosbags` package (an independent writer: rosbag2's format, MCAP storage,
CDR messages with their ros2msg schemas), for crates/locus/tests/bag.rs.

    python3 scripts/locus_csv_to_bag.py LOG.csv BAG_DIR MAPPING.toml

Topics, as a robot's recorder would write them:
  /cmd_vel     geometry_msgs/msg/Twist          each `odometry` line (logged at its time)
  /landmarks   locus_msgs/msg/LandmarkSighting  each `measurement` line, in the log's
               (header, id, range, bearing)     order, stamped with its time, frame `camera`
  /tf_static   tf2_msgs/msg/TFMessage           base_link -> camera: the `sensor` line
  /mocap/pose  geometry_msgs/msg/PoseStamped    each `truth` line (heading as a quaternion)
MAPPING.toml maps them for `locus replay bag` and holds the landmark map.
Times: `sec = floor(t)`, `nanosec = round((t - sec) 1e9)`.
"""

import math
import sys
from pathlib import Path

from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

SIGHTING = """std_msgs/Header header
uint32 id
float64 range
float64 bearing
"""


def stamp(t):
    sec = math.floor(t)
    nanosec = round((t - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return sec, nanosec


def main(csv_path, bag_dir, mapping_path):
    ts = get_typestore(Stores.ROS2_HUMBLE)
    ts.register(get_types_from_msg(SIGHTING, "locus_msgs/msg/LandmarkSighting"))
    T = ts.types
    Time = T["builtin_interfaces/msg/Time"]
    Header = T["std_msgs/msg/Header"]
    Vector3 = T["geometry_msgs/msg/Vector3"]
    Quaternion = T["geometry_msgs/msg/Quaternion"]

    def header(t, frame):
        sec, ns = stamp(t)
        return Header(stamp=Time(sec=sec, nanosec=ns), frame_id=frame)

    def quaternion(yaw):
        return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))

    landmarks, sensor, lines = [], (0.0, 0.0, 0.0), []
    for line in Path(csv_path).read_text().splitlines():
        if not line or line.startswith("#"):
            continue
        f = line.split(",")
        if f[0] == "landmark":
            landmarks.append((int(f[1]), float(f[2]), float(f[3])))
        elif f[0] == "sensor":
            sensor = tuple(float(v) for v in f[1:4])
        elif f[0] in ("odometry", "measurement", "truth"):
            lines.append(f)
        elif f[0] != "start":
            sys.exit(f"{csv_path}: {f[0]} lines are not written to a bag")

    with Writer(bag_dir, version=8, storage_plugin=StoragePlugin.MCAP) as w:
        cmd = w.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=ts)
        sight = w.add_connection("/landmarks", "locus_msgs/msg/LandmarkSighting", typestore=ts)
        tf = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        mocap = w.add_connection("/mocap/pose", "geometry_msgs/msg/PoseStamped", typestore=ts)

        def write(conn, t, msg, kind):
            sec, ns = stamp(t)
            w.write(conn, sec * 1_000_000_000 + ns, ts.serialize_cdr(msg, kind))

        first = min(float(f[1]) for f in lines)
        mount = T["geometry_msgs/msg/TransformStamped"](
            header=header(first, "base_link"),
            child_frame_id="camera",
            transform=T["geometry_msgs/msg/Transform"](
                translation=Vector3(x=sensor[0], y=sensor[1], z=0.0),
                rotation=quaternion(sensor[2]),
            ),
        )
        write(tf, first, T["tf2_msgs/msg/TFMessage"](transforms=[mount]), "tf2_msgs/msg/TFMessage")
        for f in lines:
            t = float(f[1])
            if f[0] == "odometry":
                msg = T["geometry_msgs/msg/Twist"](
                    linear=Vector3(x=float(f[2]), y=0.0, z=0.0),
                    angular=Vector3(x=0.0, y=0.0, z=float(f[3])),
                )
                write(cmd, t, msg, "geometry_msgs/msg/Twist")
            elif f[0] == "measurement":
                msg = T["locus_msgs/msg/LandmarkSighting"](
                    header=header(t, "camera"), id=int(f[2]), range=float(f[3]), bearing=float(f[4])
                )
                write(sight, t, msg, "locus_msgs/msg/LandmarkSighting")
            else:
                pose = T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=float(f[2]), y=float(f[3]), z=0.0),
                    orientation=quaternion(float(f[4])),
                )
                msg = T["geometry_msgs/msg/PoseStamped"](header=header(t, "world"), pose=pose)
                write(mocap, t, msg, "geometry_msgs/msg/PoseStamped")

    mapping = [
        "[velocity]",
        'topic = "/cmd_vel"',
        "",
        "[landmarks]",
        'topic = "/landmarks"',
        "",
        "[truth]",
        'topic = "/mocap/pose"',
        "",
    ]
    for i, x, y in landmarks:
        mapping += ["[[landmark]]", f"id = {i}", f"x = {x!r}", f"y = {y!r}", ""]
    Path(mapping_path).write_text("\n".join(mapping))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
