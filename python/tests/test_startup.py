"""`import binbow` loads no image or video library: OpenCV's imgcodecs and
videoio (with GDAL, GStreamer, FFmpeg, HDF5 and GUI toolkits behind them) are
the binbow_media module, loaded when binbow first reads an image other than a
JPEG, a video or a .mat file."""
import os
import struct
import subprocess
import sys
import zlib

import numpy as np

HEAVY = ("libavcodec", "libgstreamer", "libgdal", "libgtk", "libhdf5", "libopencv_imgcodecs",
         "libopencv_videoio", "libopencv_highgui", "binbow_media")


def loaded_after(code):
    """The shared objects mapped in a fresh interpreter once `code` has run."""
    script = code + "\nprint(open('/proc/self/maps').read())"
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            env=os.environ.copy(), timeout=300)
    assert result.returncode == 0, result.stderr[-4000:]
    return {line.split()[-1] for line in result.stdout.splitlines()
            if len(line.split()) >= 6 and ".so" in line.split()[-1]}


def test_import_loads_no_image_or_video_library():
    objects = loaded_after("import binbow")
    assert any("_binbow" in o for o in objects), sorted(objects)
    heavy = sorted(o for o in objects if any(name in o for name in HEAVY))
    assert not heavy, heavy


def grey_png(image):
    """A grey PNG of `image` (uint8, H x W), written with the standard library."""
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    height, width = image.shape
    rows = b"".join(b"\0" + row.tobytes() for row in image)  # filter 0 on every row
    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows))
            + chunk(b"IEND", b""))


def test_reading_a_png_loads_the_module_from_the_package(tmp_path):
    image = np.random.default_rng(3).integers(0, 256, size=(120, 160), dtype=np.uint8)
    png = grey_png(image)
    for i in range(3):
        (tmp_path / f"{i}.png").write_bytes(png)
    objects = loaded_after(f"import binbow\nbinbow.detect_loops({str(tmp_path)!r})")
    assert any(o.endswith("/binbow_media.so") for o in objects), sorted(objects)
    assert any("libopencv_imgcodecs" in o for o in objects), sorted(objects)
