#!/usr/bin/env python3
"""Writes the synthetic parabola profiles in scenarios/data/ (standard library only).

There is no flight data yet. These stand-ins have the magnitudes reported for Zero-G parabolas:
a residual acceleration of a few 0.01 g that wanders at ~0.5 Hz, and the aircraft pitching nose
down at ~4 deg/s through the microgravity phase (which is what makes the net drift, paper
section 4.1). Frame: x along the net's flight axis (aircraft forward), y to the left wing, z up;
a nose-down pitch is a positive rotation about +y.
"""
import math
import os

here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenarios", "data")
os.makedirs(here, exist_ok=True)
rate = 100.0  # samples per second
duration = 20.0

with open(os.path.join(here, "parabola_gravity.csv"), "w") as f:
    f.write("# apparent gravity in the rig frame (minus the accelerometer's specific force), m/s^2\n")
    f.write("t,gx,gy,gz\n")
    for i in range(int(duration * rate) + 1):
        t = i / rate
        gx = 0.05 * math.sin(2 * math.pi * 0.31 * t + 0.4)
        gy = 0.03 * math.sin(2 * math.pi * 0.53 * t + 1.3)
        gz = -0.10 + 0.12 * math.sin(2 * math.pi * 0.47 * t) + 0.05 * math.sin(2 * math.pi * 1.7 * t)
        f.write(f"{t:.2f},{gx:.5f},{gy:.5f},{gz:.5f}\n")

with open(os.path.join(here, "parabola_gyro.csv"), "w") as f:
    f.write("# angular velocity of the rig frame, rad/s (gyro)\n")
    f.write("t,wx,wy,wz\n")
    for i in range(int(duration * rate) + 1):
        t = i / rate
        wx = 0.004 * math.sin(2 * math.pi * 0.2 * t)
        wy = math.radians(4.0) * (1.0 + 0.05 * math.sin(2 * math.pi * 0.1 * t))
        wz = 0.003 * math.sin(2 * math.pi * 0.27 * t + 0.7)
        f.write(f"{t:.2f},{wx:.6f},{wy:.6f},{wz:.6f}\n")
