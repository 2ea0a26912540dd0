#!/usr/bin/python3
"""Makes the seeded case suite of the loop detector: a sequence's frames
rotated, cropped, tilted, distorted, blurred, occluded, vignetted, its second
visit re-timed, reversed or re-lit, and routes of `binbow make-route` through
photographs no route test uses, each with its own ground truth, so that
precision and recall are measured on changes the variation suite
(scripts/make_variations.sh) does not make.

  scripts/make_cases.py --seed N [--list] [--binbow PATH] [--gt-base 0|1]
                        SOURCE_DIR GT_PAIRS OUT_DIR [CASE...]

SOURCE_DIR holds the frames (1.jpg, 2.jpg, ... or any names, in natural
order; rtabmap-samples/samples); GT_PAIRS their ground truth as "query match"
lines (0- or 1-based: from a "0-based"/"1-based" comment, else 0-based if an
index 0 appears, else --gt-base). Without CASE: every case. Each CASE becomes
OUT_DIR/CASE/frames/000000.png, ... (8-bit grey PNG, the order of the frames
is the sequence's) and OUT_DIR/CASE/ground_truth.txt ("# 0-based", then
"query match" with query > match); a route case is OUT_DIR/CASE/route/ (the
frames in route/frames) and a copy of the route's ground truth.
--list prints "name part" per case and exits. --binbow is the binbow that
makes the routes (default: binbow on PATH).

Every random choice is drawn from random.Random seeded by SHA-256 of
"SEED/CASE": a case's draws do not depend on the other cases. ffmpeg runs
single-threaded and the frames are PNG, so the same seed, sources and ffmpeg
build give byte-identical frames. A case already made for the same seed and
version of this script (OUT_DIR/CASE/.done) is not made again; another seed
makes it anew.

The cases (the sequence's frames are read in grey):
  identity       the frames as they are (decoded by ffmpeg): the reference
  rotate_D       each frame rotated in-plane by D degrees (5, 10, 20), sign
                 drawn per case, +-10% jitter per frame, then cropped to the
                 largest centred rectangle of the frame's aspect that holds
                 no corner of the rotated frame (no black corners) and scaled
                 back to the frame size: a zoom of 1.12 / 1.24 / 1.43
  crop_shift     a window of 80-90% of the frame (size drawn per case)
                 drifting smoothly over the frame (random positions every 8
                 frames, cosine-interpolated), scaled back to the frame size
  tilt           perspective: each corner of the source moved inwards by up
                 to 8% of the width and height (drawn per case), the
                 quadrilateral sent to the frame's corners (ffmpeg
                 perspective)
  barrel         barrel distortion, ffmpeg lenscorrection k1 in 0.10-0.25
                 (radius normalised to the half diagonal), cropped so no
                 unmapped pixel is left and scaled back
  motion_blur    a line kernel 5-9 px long at an angle in 0-180 degrees,
                 both drawn per frame (the camera moves differently at each)
  occlusion      an opaque box of one grey level (per case) covering 15-30%
                 of each frame, its size, aspect and position drifting
                 smoothly between frames
  vignette       ffmpeg vignette, lens angle 0.55-0.85 rad (pi/5 is 0.63)
                 and centre offset up to 5% drawn per case
  revisit_fast   the second visit at twice the speed: every other frame of it
  revisit_slow   the second visit at half the speed: each of its frames
                 followed by the mean of it and the next one (none after the
                 last)
  revisit_reverse  the second visit in reverse order
  revisit_light  gain, gamma and offset drawn per case, applied only to the
                 second visit's frames
  route_lxqt, route_mate  binbow make-route --frames 2000 --seed (drawn) through
                 the photographs of scripts/route_photographs_other.sh
The second visit starts at the first query of GT_PAIRS that has a loop (41
of the 84 rtabmap frames, 1-based). Ground truth of the re-timed cases: each
new frame stands for one source frame, a blended one for both frames it
mixes; two new frames are a loop exactly when some source frame of one and
some source frame of the other are a pair of GT_PAIRS (in either order).
Frames made from one same source frame are not a loop (GT_PAIRS never pairs a
frame with itself).
"""

# The parts ("tuning" or "validation") were assigned before any measurement
# of these cases, alternating within each kind (and across the kinds of one
# case each); no result has moved a case from one part to the other.

import argparse
import hashlib
import math
import os
import random
import re
import shutil
import subprocess
import sys

import numpy as np

VERSION = "make_cases.py 1"
PROG = "make_cases.py"

# name, part, kind, parameters
CASES = [
    ("identity", "tuning", "identity", {}),
    ("rotate_5", "tuning", "rotate", {"degrees": 5}),
    ("rotate_10", "validation", "rotate", {"degrees": 10}),
    ("rotate_20", "tuning", "rotate", {"degrees": 20}),
    ("crop_shift", "validation", "crop_shift", {}),
    ("tilt", "tuning", "tilt", {}),
    ("barrel", "validation", "barrel", {}),
    ("motion_blur", "tuning", "motion_blur", {}),
    ("occlusion", "validation", "occlusion", {}),
    ("vignette", "tuning", "vignette", {}),
    ("revisit_fast", "validation", "retime", {"mode": "fast"}),
    ("revisit_slow", "tuning", "retime", {"mode": "slow"}),
    ("revisit_reverse", "validation", "retime", {"mode": "reverse"}),
    ("revisit_light", "tuning", "revisit_light", {}),
    ("route_lxqt", "tuning", "route", {"source": "lxqt"}),
    ("route_mate", "validation", "route", {"source": "mate"}),
]


class Failure(Exception):
    pass


def case_rng(seed, name):
    digest = hashlib.sha256(f"{seed}/{name}".encode()).digest()
    return random.Random(int.from_bytes(digest[:8], "big"))


def natural_key(name):
    return [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", name)]


def run(command, data=None):
    try:
        result = subprocess.run(command, input=data, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, check=False)
    except FileNotFoundError:
        raise Failure(f"{command[0]} not found: install the Debian package "
                      f"{'ffmpeg' if command[0].startswith('ff') else command[0]}"
                      " (scripts/install-deps.sh)")
    if result.returncode != 0:
        raise Failure(f"{' '.join(command[:3])}... failed: "
                      f"{result.stderr.decode(errors='replace').strip()}")
    return result.stdout


FFMPEG = ["ffmpeg", "-nostdin", "-hide_banner", "-loglevel", "error", "-threads", "1",
          "-filter_threads", "1"]


def read_frames(source_dir):
    names = sorted((n for n in os.listdir(source_dir)
                    if n.lower().endswith((".jpg", ".jpeg", ".png", ".bmp", ".pgm"))),
                   key=natural_key)
    if not names:
        raise Failure(f"{source_dir} has no frames")
    frames = []
    size = None
    for name in names:
        path = os.path.join(source_dir, name)
        probe = run(["ffprobe", "-v", "error", "-select_streams", "v:0", "-show_entries",
                     "stream=width,height", "-of", "csv=p=0", path]).decode().split(",")
        w, h = int(probe[0]), int(probe[1])
        if size is None:
            size = (w, h)
        elif size != (w, h):
            raise Failure(f"{path} is {w}x{h}, the first frame {size[0]}x{size[1]}")
        raw = run(FFMPEG + ["-i", path, "-f", "rawvideo", "-pix_fmt", "gray", "-"])
        frames.append(np.frombuffer(raw, np.uint8).reshape(h, w))
    return np.stack(frames)


def read_pairs(path, frames, base_option):
    pairs = []
    base = None
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            if line.startswith("#"):
                if "0-based" in line:
                    base = 0
                elif "1-based" in line:
                    base = 1
                continue
            q, m = map(int, line.split()[:2])
            pairs.append((q, m))
    if base is None:
        base = base_option
    if base is None:
        if any(0 in p for p in pairs):
            base = 0
        else:
            raise Failure(f"cannot tell whether {path} is 0-based or 1-based: add a comment "
                          "line saying \"0-based\" or \"1-based\", or give --gt-base")
    pairs = [(q - base, m - base) for q, m in pairs]
    for q, m in pairs:
        if not (0 <= q < frames and 0 <= m < frames):
            raise Failure(f"{path}: pair {q + base} {m + base} outside the {frames} frames")
    if not pairs:
        raise Failure(f"{path} has no pairs")
    return pairs


def ffmpeg_filter(frames, vf):
    """frames (n, h, w) uint8 grey through the ffmpeg filter chain vf; same size out."""
    n, h, w = frames.shape
    raw = run(FFMPEG + ["-f", "rawvideo", "-pix_fmt", "gray", "-s", f"{w}x{h}", "-framerate",
                        "1", "-i", "-", "-vf", vf, "-f", "rawvideo", "-pix_fmt", "gray", "-"],
              frames.tobytes())
    out = np.frombuffer(raw, np.uint8)
    if out.size != n * h * w:
        raise Failure(f"ffmpeg filter {vf} gave {out.size} bytes for {n} frames of {w}x{h}")
    return out.reshape(n, h, w)


def write_frames(frames, directory):
    n, h, w = frames.shape
    os.makedirs(directory)
    run(FFMPEG + ["-f", "rawvideo", "-pix_fmt", "gray", "-s", f"{w}x{h}", "-framerate", "1",
                  "-i", "-", "-c:v", "png", "-pix_fmt", "gray", "-start_number", "0",
                  os.path.join(directory, "%06d.png")], frames.tobytes())


def even(x):
    return max(2, int(x) // 2 * 2)


def fit_crop(w, h, s):
    """crop of the centred s-scaled frame, then back to w x h."""
    cw, ch = even(w * s), even(h * s)
    return f"crop={cw}:{ch}:{(w - cw) // 2}:{(h - ch) // 2},scale={w}:{h}:flags=bicubic"


def smooth_track(rng, n, dims, every=8):
    """n x dims values in [0, 1]: random control points every `every` frames,
    cosine-interpolated between them."""
    controls = [[rng.random() for _ in range(dims)] for _ in range(n // every + 2)]
    out = []
    for i in range(n):
        k, t = divmod(i, every)
        a = 0.5 - 0.5 * math.cos(math.pi * t / every)
        out.append([(1 - a) * p + a * q for p, q in zip(controls[k], controls[k + 1])])
    return out


# Each maker: (rng, frames, split, params) -> (new frames, sources per new frame).

def make_identity(rng, frames, split, params):
    return frames, [[i] for i in range(len(frames))]


def make_rotate(rng, frames, split, params):
    n, h, w = frames.shape
    degrees = params["degrees"]
    sign = rng.choice([-1, 1])
    angles = [sign * degrees * (1 + rng.uniform(-0.1, 0.1)) for _ in range(n)]
    # The largest centred w x h rectangle scaled by s inside the frame rotated by
    # the largest angle of the case: s (w cos + h sin) <= w and s (w sin + h cos) <= h.
    t = math.radians(degrees * 1.1)
    s = min(w / (w * math.cos(t) + h * math.sin(t)), h / (w * math.sin(t) + h * math.cos(t)))
    out = [ffmpeg_filter(frames[i:i + 1], f"rotate=a={math.radians(a):.9f}:c=black:bilinear=1,"
                         + fit_crop(w, h, s))[0] for i, a in enumerate(angles)]
    return np.stack(out), [[i] for i in range(n)]


def make_crop_shift(rng, frames, split, params):
    n, h, w = frames.shape
    s = rng.uniform(0.80, 0.90)
    cw, ch = even(w * s), even(h * s)
    out = []
    for i, (u, v) in enumerate(smooth_track(rng, n, 2)):
        x, y = round(u * (w - cw)), round(v * (h - ch))
        out.append(ffmpeg_filter(frames[i:i + 1],
                                 f"crop={cw}:{ch}:{x}:{y},scale={w}:{h}:flags=bicubic")[0])
    return np.stack(out), [[i] for i in range(n)]


def make_tilt(rng, frames, split, params):
    n, h, w = frames.shape
    dx = [rng.uniform(0, 0.08) * w for _ in range(4)]
    dy = [rng.uniform(0, 0.08) * h for _ in range(4)]
    # corners: 0 top left, 1 top right, 2 bottom left, 3 bottom right, moved inwards
    xs = [dx[0], w - dx[1], dx[2], w - dx[3]]
    ys = [dy[0], dy[1], h - dy[2], h - dy[3]]
    vf = "perspective=" + ":".join(f"x{i}={xs[i]:.3f}:y{i}={ys[i]:.3f}" for i in range(4)) \
        + ":interpolation=cubic:sense=source"
    return ffmpeg_filter(frames, vf), [[i] for i in range(n)]


def make_barrel(rng, frames, split, params):
    n, h, w = frames.shape
    k1 = rng.uniform(0.10, 0.25)
    # lenscorrection samples the source at r (1 + k1 r^2), r = 1 at the corners: the
    # centred rectangle scaled by s stays inside when s (1 + k1 s^2) <= 1.
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if mid * (1 + k1 * mid * mid) <= 1 else (lo, mid)
    vf = f"lenscorrection=k1={k1:.6f}:k2=0:i=bilinear," + fit_crop(w, h, lo * 0.995)
    return ffmpeg_filter(frames, vf), [[i] for i in range(n)]


def line_kernel(length, degrees):
    size = length // 2 * 2 + 3
    kernel = np.zeros((size, size), np.float64)
    c = size // 2
    dx, dy = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    samples = 8 * length
    for k in range(samples):
        t = (k + 0.5) / samples * (length - 1) - (length - 1) / 2
        x, y = c + t * dx, c + t * dy
        x0, y0 = math.floor(x), math.floor(y)
        fx, fy = x - x0, y - y0
        kernel[y0, x0] += (1 - fx) * (1 - fy)
        kernel[y0, x0 + 1] += fx * (1 - fy)
        kernel[y0 + 1, x0] += (1 - fx) * fy
        kernel[y0 + 1, x0 + 1] += fx * fy
    return kernel / kernel.sum()


def convolve(image, kernel):
    size = kernel.shape[0]
    r = size // 2
    h, w = image.shape
    padded = np.pad(image.astype(np.float64), r, mode="edge")
    out = np.zeros((h, w), np.float64)
    for dy in range(size):
        for dx in range(size):
            if kernel[dy, dx] > 0:
                out += kernel[dy, dx] * padded[dy:dy + h, dx:dx + w]
    return np.clip(np.floor(out + 0.5), 0, 255).astype(np.uint8)


def make_motion_blur(rng, frames, split, params):
    out = []
    for frame in frames:
        length, degrees = rng.randint(5, 9), rng.uniform(0, 180)
        out.append(convolve(frame, line_kernel(length, degrees)))
    return np.stack(out), [[i] for i in range(len(frames))]


def make_occlusion(rng, frames, split, params):
    n, h, w = frames.shape
    grey = rng.randrange(256)
    out = frames.copy()
    for i, (u, v, a, r) in enumerate(smooth_track(rng, n, 4, every=6)):
        area = (0.15 + 0.15 * a) * w * h
        aspect = math.exp(math.log(0.5) + r * math.log(4))  # box width / height, 0.5-2
        bw = min(w, math.sqrt(area * aspect))
        bh = min(h, area / bw)
        bw = area / bh
        bw, bh = min(w, round(bw)), min(h, round(bh))
        x, y = round(u * (w - bw)), round(v * (h - bh))
        out[i, y:y + bh, x:x + bw] = grey
    return out, [[i] for i in range(n)]


def make_vignette(rng, frames, split, params):
    n, h, w = frames.shape
    angle = rng.uniform(0.55, 0.85)
    x0 = w / 2 + rng.uniform(-0.05, 0.05) * w
    y0 = h / 2 + rng.uniform(-0.05, 0.05) * h
    vf = f"vignette=a={angle:.6f}:x0={x0:.3f}:y0={y0:.3f}:dither=0"
    return ffmpeg_filter(frames, vf), [[i] for i in range(n)]


def make_retime(rng, frames, split, params):
    n = len(frames)
    first = list(range(split))
    second = list(range(split, n))
    mode = params["mode"]
    if mode == "fast":
        sources = [[i] for i in first + second[::2]]
    elif mode == "reverse":
        sources = [[i] for i in first + second[::-1]]
    else:  # slow
        sources = [[i] for i in first]
        for k, i in enumerate(second):
            sources.append([i])
            if k + 1 < len(second):
                sources.append([i, i + 1])
    out = []
    for s in sources:
        if len(s) == 1:
            out.append(frames[s[0]])
        else:
            a, b = frames[s[0]].astype(np.uint16), frames[s[1]].astype(np.uint16)
            out.append(((a + b + 1) // 2).astype(np.uint8))
    return np.stack(out), sources


def make_revisit_light(rng, frames, split, params):
    gain = math.exp(rng.choice([-1, 1]) * rng.uniform(0.2, 0.45))
    gamma = math.exp(rng.choice([-1, 1]) * rng.uniform(0.15, 0.35))
    offset = rng.uniform(-20, 20)
    lut = np.array([min(255, max(0, math.floor(gain * 255 * (v / 255) ** gamma + offset + 0.5)))
                    for v in range(256)], np.uint8)
    out = frames.copy()
    out[split:] = lut[frames[split:]]
    return out, [[i] for i in range(len(frames))]


MAKERS = {
    "identity": make_identity, "rotate": make_rotate, "crop_shift": make_crop_shift,
    "tilt": make_tilt, "barrel": make_barrel, "motion_blur": make_motion_blur,
    "occlusion": make_occlusion, "vignette": make_vignette, "retime": make_retime,
    "revisit_light": make_revisit_light,
}


def derived_pairs(sources, pairs):
    same = set()
    for q, m in pairs:
        same.add((q, m))
        same.add((m, q))
    out = []
    for i in range(len(sources)):
        for j in range(i):
            if any((a, b) in same for a in sources[i] for b in sources[j]):
                out.append((i, j))
    return out


def write_ground_truth(path, pairs):
    with open(path, "w") as f:
        f.write("# 0-based\n")
        for q, m in pairs:
            f.write(f"{q} {m}\n")


def make_route(rng, name, params, directory, binbow):
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "route_photographs_other.sh")
    result = subprocess.run([script, params["source"]], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, check=False)
    if result.returncode != 0:
        raise Failure(result.stderr.decode(errors="replace").strip())
    photographs = result.stdout.decode().split("\n")
    photographs = [p for p in photographs if p]
    route_seed = rng.randrange(1, 2 ** 31)
    route = os.path.join(directory, "route")
    try:
        run([binbow, "make-route", "--frames", "2000", "--seed", str(route_seed), "-o", route]
            + photographs)
    except Failure as e:
        raise Failure(f"{name}: {e}")
    with open(os.path.join(route, "ground_truth.txt")) as f:
        lines = [line for line in f if line.strip() and not line.startswith("#")]
    with open(os.path.join(directory, "ground_truth.txt"), "w") as f:
        f.write("# 0-based\n")
        f.writelines(lines)
    return f"route seed {route_seed}, {len(photographs)} photographs"


def main():
    parser = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--binbow", default="binbow")
    parser.add_argument("--gt-base", type=int, choices=[0, 1])
    parser.add_argument("source_dir", nargs="?")
    parser.add_argument("gt_pairs", nargs="?")
    parser.add_argument("out_dir", nargs="?")
    parser.add_argument("cases", nargs="*")
    args = parser.parse_args()
    if args.list:
        for name, part, _, _ in CASES:
            print(name, part)
        return 0
    if args.out_dir is None:
        parser.error("SOURCE_DIR, GT_PAIRS and OUT_DIR are required")
    known = {c[0]: c for c in CASES}
    for name in args.cases:
        if name not in known:
            print(f"{PROG}: error: unknown case {name} (--list lists them)", file=sys.stderr)
            return 2
    wanted = args.cases or [c[0] for c in CASES]
    stamp = f"seed {args.seed}\nversion {VERSION}\n"
    todo = []
    for name in wanted:
        done = os.path.join(args.out_dir, name, ".done")
        if os.path.isfile(done) and open(done).read() == stamp:
            continue
        todo.append(name)
    if not todo:
        return 0
    for tool in ("ffmpeg", "ffprobe"):
        if shutil.which(tool) is None:
            raise Failure(f"{tool} not found: install the Debian package ffmpeg "
                          "(scripts/install-deps.sh)")
    frames = pairs = split = None
    for name in todo:
        _, part, kind, params = known[name]
        directory = os.path.join(args.out_dir, name)
        shutil.rmtree(directory, ignore_errors=True)
        os.makedirs(directory)
        rng = case_rng(args.seed, name)
        if kind == "route":
            if shutil.which(args.binbow) is None:
                raise Failure(f"binbow not found ({args.binbow}): give --binbow")
            note = make_route(rng, name, params, directory, args.binbow)
        else:
            if frames is None:
                frames = read_frames(args.source_dir)
                pairs = read_pairs(args.gt_pairs, len(frames), args.gt_base)
                split = min(max(q, m) for q, m in pairs)
            new, sources = MAKERS[kind](rng, frames, split, params)
            write_frames(new, os.path.join(directory, "frames"))
            write_ground_truth(os.path.join(directory, "ground_truth.txt"),
                               derived_pairs(sources, pairs))
            note = f"{len(new)} frames"
        with open(os.path.join(directory, ".done"), "w") as f:
            f.write(stamp)
        print(f"{name}: {note}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except Failure as e:
        print(f"{PROG}: error: {e}", file=sys.stderr)
        sys.exit(1)
