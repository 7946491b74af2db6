#!/usr/bin/env python3
"""Writes the CDR messages of write_ros2.mjs (messages.cdr: uint64 stamp_ns, uint32 size, bytes)
as a ROS 2 bag directory of rosbag2's sqlite3 storage: metadata.yaml and one .db3 with rosbag2's
tables (topics, messages) through Python's sqlite3 (Debian's libsqlite3). Topic /velodyne_points,
sensor_msgs/msg/PointCloud2, and a second topic between its messages.

Usage: write_db3.py messages.cdr OUT_BAG_DIR"""
import os
import sqlite3
import struct
import sys

METADATA = """rosbag2_bagfile_information:
  version: 5
  storage_identifier: sqlite3
  duration:
    nanoseconds: {duration}
  starting_time:
    nanoseconds_since_epoch: {start}
  message_count: {count}
  topics_with_message_count:
    - topic_metadata:
        name: /velodyne_points
        type: sensor_msgs/msg/PointCloud2
        serialization_format: cdr
        offered_qos_profiles: ""
      message_count: {scans}
  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - {name}_0.db3
  files:
    - path: {name}_0.db3
"""


def main():
    blobs, out = sys.argv[1:3]
    os.makedirs(out)
    name = os.path.basename(os.path.normpath(out))
    db = sqlite3.connect(os.path.join(out, name + "_0.db3"))
    db.executescript("""
        CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
        CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                            serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
        CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL, data BLOB NOT NULL);
        CREATE INDEX timestamp_idx ON messages (timestamp ASC);
        INSERT INTO schema VALUES (3, 'humble');
        INSERT INTO topics VALUES (1, '/chatter', 'std_msgs/msg/String', 'cdr', '');
        INSERT INTO topics VALUES (2, '/velodyne_points', 'sensor_msgs/msg/PointCloud2', 'cdr', '');
    """)
    stamps = []
    with open(blobs, "rb") as f:
        while head := f.read(12):
            stamp, size = struct.unpack("<QI", head)
            db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (1, ?, ?)", (stamp, b"\0\1\0\0\2\0\0\0h\0"))
            db.execute("INSERT INTO messages (topic_id, timestamp, data) VALUES (2, ?, ?)", (stamp, f.read(size)))
            stamps.append(stamp)
    db.commit()
    db.close()
    with open(os.path.join(out, "metadata.yaml"), "w") as m:
        m.write(METADATA.format(duration=stamps[-1] - stamps[0], start=stamps[0], count=2 * len(stamps), scans=len(stamps), name=name))


if __name__ == "__main__":
    main()
