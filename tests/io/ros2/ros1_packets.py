#!/usr/bin/env python3
"""Reads the Ouster driver's topics of a ROS 1 bag with ROS's own reader (Debian's python3-rosbag):
the lidar and IMU packets (ouster_ros/PacketMsg, uint8[] buf) and the metadata (std_msgs/String),
and writes them for write_packets.mjs, each as: uint16 length + topic, uint64 stamp_ns, uint32
length + payload (the packet's bytes, or the metadata's text).

Usage: ros1_packets.py IN.bag OUT.msgs"""
import struct
import sys

import rosbag


def main():
    bag_path, out_path = sys.argv[1:3]
    with rosbag.Bag(bag_path) as bag, open(out_path, "wb") as out:
        for topic, msg, t in bag.read_messages():
            payload = msg.data.encode() if topic.endswith("/metadata") else bytes(msg.buf)
            out.write(struct.pack("<H", len(topic)) + topic.encode() + struct.pack("<QI", t.to_nsec(), len(payload)) + payload)


if __name__ == "__main__":
    main()
