#!/usr/bin/env python3
"""Seeds for `netlab label`: the four corner knots of the first frame in each camera, taken from
a rendered shot's truth.h5 (standing for a person's 16 clicks), written as a DLTdv8-style
xypts.csv with only the corners' columns: a row per frame number (a row of NaN for each frame
before the shot's first, whose number is truth.h5's /frame_index[0]), the last one filled.

usage: seed_corners.py truth.h5 ROWSxCOLS out.csv CAMERA...   (cameras in the experiment's order)

Reads the HDF5 file with h5dump (Debian's hdf5-tools), raw little-endian, so no Python HDF5
module is needed. A corner outside a camera's image in the first frame (visibility 2) or
hidden behind a solid (visibility 1: the target) is NaN, as a person would leave it: `netlab
label` starts from three corners as well as four.
"""
import os
import struct
import subprocess
import sys
import tempfile


def dump(path, dataset, start, count, fmt):
    """The hyperslab start/count of `dataset` as a flat list of `fmt` values."""
    with tempfile.TemporaryDirectory() as tmp:
        raw = os.path.join(tmp, "raw.bin")
        subprocess.run(["h5dump", "-d", dataset, "-s", ",".join(map(str, start)), "-c",
                        ",".join(map(str, count)), "-b", "LE", "-o", raw, path],
                       check=True, stdout=subprocess.DEVNULL)
        data = open(raw, "rb").read()
    size = struct.calcsize("<" + fmt)
    return list(struct.unpack("<" + fmt * (len(data) // size), data))


def main():
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    truth, shape, out, cameras = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
    rows, cols = (int(n) for n in shape.lower().split("x"))
    knots = rows * cols
    corners = [0, cols - 1, (rows - 1) * cols, knots - 1]  # row-major knot index
    first_frame = dump(truth, "/frame_index", (0,), (1,), "i")[0]
    header, values = [], []
    for k in corners:
        for c, camera in enumerate(cameras):
            px = dump(truth, f"/cameras/{camera}/knots_px", (0, 0, 0), (1, knots, 2), "d")
            visibility = dump(truth, f"/cameras/{camera}/visibility", (0, 0), (1, knots), "B")
            column = f"pt{k + 1}_cam{c + 1}"
            header += [column + "_X", column + "_Y"]
            seen = visibility[k] == 0
            values += [repr(px[2 * k]) if seen else "NaN", repr(px[2 * k + 1]) if seen else "NaN"]
    empty = ",".join(["NaN"] * len(header)) + "\n"
    with open(out, "w") as f:
        f.write(",".join(header) + "\n" + empty * first_frame + ",".join(values) + "\n")


if __name__ == "__main__":
    main()
