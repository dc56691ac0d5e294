#!/usr/bin/env python3
"""Writes the committed seeds of the generated inputs (tests/fuzz/corpus/TARGET/): CAN frame
sequences, control-socket requests, depth frames and ROS depth images, in the layouts the
targets read (tests/fuzz/*.cpp). Run from anywhere: python3 tests/fuzz/make_seeds.py."""
import pathlib
import struct

HERE = pathlib.Path(__file__).resolve().parent


def write(target, name, data):
    d = HERE / "corpus" / target
    d.mkdir(parents=True, exist_ok=True)
    (d / name).write_bytes(data if isinstance(data, bytes) else data.encode())


def can_frame(can_id, data, dlc=8):
    data = bytearray(data[:7].ljust(7, b"\0"))
    s = (can_id & 0xFF) + ((can_id >> 8) & 0x7) + sum(data)
    data.append((0xFF - s) & 0xFF)
    return struct.pack("<IB", can_id, dlc) + bytes(data)


def i16(v, big):
    return struct.pack(">h" if big else "<h", v)


def u16(v, big):
    return struct.pack(">H" if big else "<H", v)


for big in (False, True):
    frames = [
        can_frame(0x110, i16(500, big) + i16(-300, big) + bytes([1, 0, 1])),  # command, enable
        can_frame(0x100, bytes([1, 0, 0, 0, 0, 0, 2])),                         # host heartbeat
        can_frame(0x210, i16(498, big) + i16(-301, big) + u16(10000, big) + bytes([3])),  # odometry
        can_frame(0x220, bytes([1]) + u16(0, big) + bytes([0, 0, 0, 4])),      # status
        can_frame(0x200, bytes([0, 0, 0, 0, 0, 0, 5])),                         # base heartbeat
        struct.pack("<IB", 0x20000040 | 0x4, 8) + bytes(8),                     # error frame: bus-off
    ]
    write("can_codec", "frames-big" if big else "frames-little", bytes([1 if big else 0]) + b"".join(frames))

requests = {
    "goal": '{"cmd": "goal", "x": 3.0, "y": 4.5, "theta": 1.57}',
    "goal-no-theta": '{"cmd": "goal", "x": -1e-3, "y": 12}',
    "pose": '{"cmd": "pose", "x": 1.0, "y": 1.0, "theta": 0.0}',
    "stop": '{"cmd": "stop"}',
    "status": '{"cmd":"status"}',
    "debug-overrun": '{"debug": "overrun", "ms": 80}',
    "debug-stall": '{"debug": "stall_obstacles", "on": true}',
}
for name, line in requests.items():
    write("protocol", name, line)

# depth_perception: robot x, y, theta; flags; mount x, y, z, roll, pitch, yaw; depths (mm).
def depth_seed(flags, depths, robot=(2.0, 4.5, 0.0), mount=(0.0, 0.0, 1.0, 0.0, 0.3, 0.0)):
    return struct.pack("<3dB6d", *robot, flags, *mount) + struct.pack("<%dH" % len(depths), *depths)


write("depth_perception", "wall-1500", depth_seed(0, [1500] * 64))
write("depth_perception", "ramp", depth_seed(0, list(range(400, 6000, 50))))
write("depth_perception", "box-and-holes", depth_seed(0, [0] * 20 + [1800] * 12 + [0] * 8 + [65535]))
write("depth_perception", "own-mount", depth_seed(7, [2000] * 32, robot=(5.0, 3.0, 1.0), mount=(0.1, 0.0, 1.1, 0.0, 0.4, 0.2)))
# Flag 8: staa-sim's agents' settings, the robot turning away from what it saw (kept tracks).
write("depth_perception", "agent-kept", depth_seed(8, [0] * 20 + [1800] * 12 + [0] * 8))
write("depth_perception", "agent-kept-near", depth_seed(8, [0] * 30 + [700] * 6, robot=(4.5, 4.5, 0.0)))

# ros_depth_image: flags; (camera_info / pose fields by flags); shape; stamps; pixel bytes.
def image_seed(shape, pixels, flags=0, stamp=1_000_000_000, received=1_010_000_000):
    return bytes([flags, shape]) + struct.pack("<qq", stamp, received) + pixels


write("ros_depth_image", "16uc1", image_seed(0, struct.pack("<8H", 0, 800, 1500, 2500, 4000, 65535, 1200, 1300)))
write("ros_depth_image", "32fc1", image_seed(1, struct.pack("<6f", float("nan"), 0.8, 1.5, float("inf"), -1.0, 70.0)))
write("ros_depth_image", "32fc1-big-endian", image_seed(1 | 32, struct.pack(">4f", 1.0, 2.0, 3.0, 4.0)))
write("ros_depth_image", "no-camera-info", image_seed(0, struct.pack("<2H", 1000, 2000), flags=8))
