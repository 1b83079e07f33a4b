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
  /mocap/pose  geometry_msgs/msg/PoseStamped    each `truth` line (heading as a quaternion;
                                                identity for a truth of positions only)
  /scanN       sensor_msgs/msg/LaserScan        each `scan` line of a many-beam sensor N
  /rangeN      sensor_msgs/msg/Range            each `scan` line of a one-beam sensor N
               (frame `beamN`, its mount in /tf_static; `max` as +inf, `-` as NaN)
MAPPING.toml maps them for `locus replay bag` and holds the landmark map, the
walls, and the map file's path (made absolute). A `start` line has no place in a bag and is not written.
Times: `sec = floor(t)`, `nanosec = round((t - sec) 1e9)`; a log time before 0
is logged at 0 (its stamp keeps it).
"""

import math
import sys

import numpy
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

    landmarks, sensor, lines, walls, beams, map_file = [], (0.0, 0.0, 0.0), [], [], {}, None
    for line in Path(csv_path).read_text().splitlines():
        if not line or line.startswith("#"):
            continue
        f = line.split(",")
        if f[0] == "landmark":
            landmarks.append((int(f[1]), float(f[2]), float(f[3])))
        elif f[0] == "sensor":
            sensor = tuple(float(v) for v in f[1:4])
        elif f[0] in ("odometry", "measurement", "truth", "scan"):
            lines.append(f)
        elif f[0] == "map":
            map_file = (Path(csv_path).parent / f[1]).resolve()
        elif f[0] == "wall":
            walls.append(tuple(float(v) for v in f[1:5]))
        elif f[0] == "beam_sensor":
            beams[int(f[1])] = [float(v) for v in f[2:9]] + [int(f[9])]
        elif f[0] != "start":
            sys.exit(f"{csv_path}: {f[0]} lines are not written to a bag")

    with Writer(bag_dir, version=8, storage_plugin=StoragePlugin.MCAP) as w:
        cmd = w.add_connection("/cmd_vel", "geometry_msgs/msg/Twist", typestore=ts)
        sight = w.add_connection("/landmarks", "locus_msgs/msg/LandmarkSighting", typestore=ts)
        tf = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts)
        mocap = w.add_connection("/mocap/pose", "geometry_msgs/msg/PoseStamped", typestore=ts)

        def write(conn, t, msg, kind):
            sec, ns = stamp(t)
            w.write(conn, max(0, sec * 1_000_000_000 + ns), ts.serialize_cdr(msg, kind))

        def mount(t, frame, x, y, yaw):
            return T["geometry_msgs/msg/TransformStamped"](
                header=header(t, "base_link"),
                child_frame_id=frame,
                transform=T["geometry_msgs/msg/Transform"](
                    translation=Vector3(x=x, y=y, z=0.0), rotation=quaternion(yaw)
                ),
            )

        first = min(float(f[1]) for f in lines)
        mounts = [mount(first, "camera", *sensor)]
        beam_conn = {}
        for i, (x, y, yaw, lo, hi, a0, step, count) in beams.items():
            mounts.append(mount(first, f"beam{i}", x, y, yaw))
            kind = "sensor_msgs/msg/Range" if count == 1 else "sensor_msgs/msg/LaserScan"
            name = f"/range{i}" if count == 1 else f"/scan{i}"
            beam_conn[i] = (w.add_connection(name, kind, typestore=ts), kind, name)
        write(tf, first, T["tf2_msgs/msg/TFMessage"](transforms=mounts), "tf2_msgs/msg/TFMessage")
        heading = all(len(f) == 5 for f in lines if f[0] == "truth")

        def value(r):
            return math.inf if r == "max" else math.nan if r == "-" else float(r)
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
            elif f[0] == "scan":
                i = int(f[2])
                x, y, yaw, lo, hi, a0, step, count = beams[i]
                conn, kind, _ = beam_conn[i]
                ranges = [value(r) for r in f[3:]]
                if count == 1:
                    msg = T[kind](
                        header=header(t, f"beam{i}"), radiation_type=1, field_of_view=0.0,
                        min_range=lo, max_range=hi, range=ranges[0],
                    )
                else:
                    msg = T[kind](
                        header=header(t, f"beam{i}"), angle_min=a0, angle_max=a0 + (count - 1) * step,
                        angle_increment=step, time_increment=0.0, scan_time=0.0, range_min=lo,
                        range_max=hi, ranges=numpy.array(ranges, dtype=numpy.float32),
                        intensities=numpy.array([], dtype=numpy.float32),
                    )
                write(conn, t, msg, kind)
            else:
                theta = float(f[4]) if heading else 0.0
                pose = T["geometry_msgs/msg/Pose"](
                    position=T["geometry_msgs/msg/Point"](x=float(f[2]), y=float(f[3]), z=0.0),
                    orientation=quaternion(theta),
                )
                msg = T["geometry_msgs/msg/PoseStamped"](header=header(t, "world"), pose=pose)
                write(mocap, t, msg, "geometry_msgs/msg/PoseStamped")

    mapping = [f"map = {str(map_file)!r}", ""] if map_file else []
    mapping += [
        "[velocity]",
        'topic = "/cmd_vel"',
        "",
        "[truth]",
        'topic = "/mocap/pose"',
        "" if heading else 'orientation = ""',
        "",
    ]
    if any(f[0] == "measurement" for f in lines):
        mapping += ["[landmarks]", 'topic = "/landmarks"', ""]
    for i, (*_, count) in beams.items():
        mapping += ["[[range]]" if count == 1 else "[[scan]]", f'topic = "/{"range" if count == 1 else "scan"}{i}"', ""]
    for x1, y1, x2, y2 in walls:
        mapping += ["[[wall]]", f"x1 = {x1!r}", f"y1 = {y1!r}", f"x2 = {x2!r}", f"y2 = {y2!r}", ""]
    for i, x, y in landmarks:
        mapping += ["[[landmark]]", f"id = {i}", f"x = {x!r}", f"y = {y!r}", ""]
    Path(mapping_path).write_text("\n".join(mapping))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
