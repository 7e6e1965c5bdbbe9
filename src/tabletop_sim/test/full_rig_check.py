#!/usr/bin/env python3
"""Listens to the pipeline of launch/full_rig.launch for a while and checks what came through
(test_full_rig_two_hosts.sh): frame sets with every camera's image and its camera_info, and
pSfS body volumes. Prints one summary line; exit 0 = passed, 1 = failed (the reason printed).

  full_rig_check.py CAMERAS SECONDS MIN_SETS MIN_BODY_LITRES
"""
import sys
import time

import rospy
from tabletop_msgs.msg import MultiViewFrame, VoxelVolume


def main():
    cameras, seconds, min_sets, min_litres = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), float(sys.argv[4])
    rospy.init_node("full_rig_check", anonymous=True)
    stats = {"sets": 0, "complete": 0, "bad_info": 0, "volumes": 0, "max_litres": 0.0, "spread": 0.0}

    def on_frames(msg):
        stats["sets"] += 1
        present = [i for i, im in enumerate(msg.images) if im.width > 0]
        if len(msg.images) == cameras and len(present) == cameras:
            stats["complete"] += 1
        stamps = [msg.images[i].header.stamp.to_sec() for i in present]
        if stamps:
            stats["spread"] = max(stats["spread"], max(stamps) - min(stamps))
        for i in present:
            info = msg.camera_infos[i]
            # The capture host's camera_info: the rig camera of that name, the image's size.
            if (info.width != msg.images[i].width or info.height != msg.images[i].height or
                    info.K[0] <= 0 or info.header.frame_id != "cam%d_optical_frame" % i):
                stats["bad_info"] += 1

    def on_volume(msg):
        stats["volumes"] += 1
        occupied = sum(1 for v in bytearray(msg.data) if v >= 128)
        stats["max_litres"] = max(stats["max_litres"], occupied * msg.voxel_size ** 3 * 1000.0)

    rospy.Subscriber("/tabletop/frames", MultiViewFrame, on_frames, queue_size=50)
    rospy.Subscriber("/tabletop/psfs/body_volume", VoxelVolume, on_volume, queue_size=10)
    end = time.time() + seconds
    while time.time() < end and not rospy.is_shutdown():
        time.sleep(0.1)
    print("[full_rig_check] %d frame sets (%d complete, widest stamp spread %.1f ms), %d with a "
          "wrong camera_info; %d body volumes, largest body %.1f l"
          % (stats["sets"], stats["complete"], stats["spread"] * 1e3, stats["bad_info"],
             stats["volumes"], stats["max_litres"]))
    failures = []
    if stats["complete"] < min_sets:
        failures.append("only %d complete frame sets (at least %d expected)" % (stats["complete"], min_sets))
    if stats["bad_info"]:
        failures.append("%d images with a camera_info that does not match" % stats["bad_info"])
    if stats["max_litres"] < min_litres:
        failures.append("largest body volume %.1f l (the person is about 30 l; at least %.1f expected)"
                        % (stats["max_litres"], min_litres))
    for f in failures:
        print("[full_rig_check] FAILED: " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
