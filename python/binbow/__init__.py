"""Bags of binary words for fast place recognition (Galvez-Lopez & Tardos 2012).

Descriptors are numpy uint8 arrays of shape (n, code_size), one row per
feature, as OpenCV's ORB and BRIEF return them; None (what OpenCV returns for
an image without keypoints) is an image with no features.
"""

import os as _os
import sys as _sys
import time as _time
import warnings as _warnings

from . import _data_location
from ._binbow import (
    BowVector,
    BuildProgress,
    Database,
    DatabaseLock,
    Error,
    Evaluation,
    FeatureExtractor,
    GroundTruth,
    LoopDetector,
    LoopDetectorParams,
    LoopResult,
    SimilarityMatrix,
    Vocabulary,
    WriteConflict,
    __version__,
    _detect_loops,
    _saved_state,
    evaluate,
    _write_report,
    hamming,
)

__all__ = [
    "BowVector",
    "BuildProgress",
    "Database",
    "DatabaseLock",
    "Error",
    "Evaluation",
    "FeatureExtractor",
    "GroundTruth",
    "LoopDetector",
    "LoopDetectorParams",
    "LoopResult",
    "LoopResults",
    "SimilarityMatrix",
    "Vocabulary",
    "WriteConflict",
    "data_directories",
    "detect_loops",
    "evaluate",
    "hamming",
    "write_report",
]

_DEFAULT_DESCRIPTORS = ("orb", "brief")


def data_directories():
    """The folders searched for binbow's bundled data (vocab/...), in order.

    $BINBOW_DATA_DIR when set, then the data installed with this package:
    inside it (pip), <prefix>/share/binbow (cmake --install) or the build
    tree's share/binbow.
    """
    package = _os.path.dirname(_os.path.abspath(__file__))
    bundled = _os.path.normpath(_os.path.join(package, _data_location.DATA_DIRECTORY))
    override = _os.environ.get("BINBOW_DATA_DIR")
    return [_os.path.normpath(override), bundled] if override else [bundled]


def _default_vocabulary_file(descriptor):
    """The file of the bundled default vocabulary of "orb" or "brief" descriptors."""
    if descriptor not in _DEFAULT_DESCRIPTORS:
        raise ValueError(
            f"no default vocabulary for descriptor {descriptor!r}: choose one of "
            + ", ".join(repr(d) for d in _DEFAULT_DESCRIPTORS)
        )
    candidates = [
        _os.path.join(directory, "vocab", f"{descriptor}_default.bbw")
        for directory in data_directories()
    ]
    for path in candidates:
        if _os.path.isfile(path):
            return path
    raise FileNotFoundError(
        f"the default {descriptor} vocabulary is not installed; set BINBOW_DATA_DIR to binbow's "
        "data folder (the repository's data/). Searched: " + ", ".join(candidates)
    )


def _default_vocabulary(descriptor="orb"):
    """The bundled default vocabulary of "orb" or "brief" descriptors.

    Searched in vocab/ of each of data_directories(); FileNotFoundError names
    the places searched when it is not installed.
    """
    return Vocabulary.load(_default_vocabulary_file(descriptor))


Vocabulary.default = staticmethod(_default_vocabulary)


class _CliProgress:
    """The CLI's progress line on stderr: redrawn in place on a terminal;
    elsewhere (a log file, CI) no redraws, a plain line every LOG_INTERVAL
    seconds while a stage runs; and a closing line."""

    LOG_INTERVAL = 10.0

    def __init__(self, label):
        self._label = label
        self._tty = _sys.stderr.isatty()
        self._start = _time.monotonic()
        self._last_draw = self._start
        self._done = 0

    def __call__(self, done, total):
        self._done = done
        now = _time.monotonic()
        seconds = now - self._start
        if self._tty:
            if now - self._last_draw < 0.1 and done != total:
                return
            self._last_draw = now
            if total:
                filled = 30 * done // total
                bar = "=" * filled + " " * (30 - filled)
                _sys.stderr.write(f"\r{self._label} [{bar}] {done}/{total} {seconds:.1f}s")
            else:
                _sys.stderr.write(f"\r{self._label} {done} {seconds:.1f}s")
            _sys.stderr.flush()
            return
        if now - self._last_draw < self.LOG_INTERVAL:
            return
        self._last_draw = now
        if total:
            percent = 100 * done // total
            _sys.stderr.write(f"{self._label}: {done}/{total} ({percent}%) {seconds:.1f}s\n")
        else:
            _sys.stderr.write(f"{self._label}: {done} {seconds:.1f}s\n")
        _sys.stderr.flush()

    def finish(self):
        seconds = _time.monotonic() - self._start
        if self._tty:
            _sys.stderr.write("\r\033[K")
        _sys.stderr.write(f"{self._label}: {self._done} done in {seconds:.2f}s\n")
        _sys.stderr.flush()


def detect_loops(
    inputs,
    vocabulary=None,
    descriptor=None,
    params=None,
    progress=False,
    *,
    max_features=None,
    stride=1,
    max_width=0,
    video_fps=0.0,
    resume_state=None,
    save_state=None,
    skip_unreadable=False,
    threads=0,
):
    """Loop closures of an image sequence: what `binbow detect-loops` finds.

    inputs: a path or a list of paths of image files, folders (their images in
    natural order: 2.jpg before 10.jpg), videos (frames named "video.mp4#N") or
    text lists of images. vocabulary: None for Vocabulary.default(descriptor),
    a Vocabulary, or "online": no pre-trained vocabulary, the words grow from
    the sequence itself (LoopDetector.online, `detect-loops --online-vocabulary`).
    descriptor: the extractor (None: the one the vocabulary records, else
    "orb"), "orb", "brief", "akaze" or "brisk", with
    the CLI's defaults (max_features: None for the extractor's default), or a
    FeatureExtractor configured otherwise. params: a
    LoopDetectorParams, a parameter file (JSON or YAML, as --params: keys it
    omits keep the defaults) or None: the paper's parameters, whose frame
    counts follow the frames processed per second of a video. progress: True
    prints the CLI's progress on stderr; a callable is called with (done,
    total) after each frame, total None when not known beforehand. stride,
    max_width and video_fps thin the frames out as the CLI's options do.
    skip_unreadable: an image that cannot be read (damaged, truncated) is a
    warning (UserWarning naming the file and the reason) instead of an error:
    its LoopResult keeps the frame's index, with status "unreadable" and
    .unreadable the reason, and matches nothing (as `--skip-unreadable`).
    threads: threads reading and describing frames ahead of the detector, which
    takes them in order (0: every core; as `--threads`): the results are the
    same for any number.

    save_state: a .bbld file to save the detector's state to after the last
    frame (LoopDetector.save; its folder is created). resume_state: a .bbld
    file saved so, to go on from: the frames continue its numbering, and its
    loops can close with the frames it saw (as `detect-loops --resume-state`).
    Its kind and descriptor are taken from the file: vocabulary may be None
    (the default vocabulary of its descriptor, or "online" for an online
    state) or the Vocabulary it ran with; params must be None (the state
    keeps its own). ValueError when an argument contradicts the state.

    Returns a LoopResults: one LoopResult per frame, in order, with its file
    name, and what the run used. The GIL is released while frames are read and
    processed; Ctrl-C stops the run.
    """
    if isinstance(inputs, (str, bytes, _os.PathLike)):
        inputs = [inputs]
    paths = []
    for index, item in enumerate(inputs):
        if not isinstance(item, (str, bytes, _os.PathLike)):
            raise TypeError(f"inputs[{index}] must be a path, got {type(item).__name__}")
        paths.append(_os.fsdecode(item))
    resumed_frames = 0
    if resume_state is not None:
        resume_state, resumed_frames, vocabulary, descriptor = _resume(
            resume_state, vocabulary, descriptor, params
        )
    if save_state is not None:
        save_state = _path("save_state", save_state)
    if descriptor is None:  # the vocabulary's extractor, as the CLI takes it
        recorded = vocabulary.descriptor if isinstance(vocabulary, Vocabulary) else ""
        descriptor = recorded or "orb"
    name = descriptor.descriptor if isinstance(descriptor, FeatureExtractor) else descriptor
    recorded = vocabulary.descriptor if isinstance(vocabulary, Vocabulary) else ""
    if recorded and isinstance(name, str) and name.lower() != recorded:
        try:
            FeatureExtractor(name)
        except ValueError:
            pass  # an unknown name: refused below as such
        else:
            raise ValueError(f"the vocabulary was trained on {recorded} descriptors, not "
                             f"{name}: pass descriptor=\"{recorded}\" or a vocabulary trained "
                             f"on {name}")
    vocabulary_file = None
    online = isinstance(vocabulary, str) and vocabulary == "online"
    if online:
        vocabulary = None
    elif vocabulary is None:
        vocabulary_file = _default_vocabulary_file(name)
        vocabulary = Vocabulary.load(vocabulary_file)
    printer = None
    if progress is True:
        printer = _CliProgress("detecting loops")
        callback = printer
    elif progress is False or progress is None:
        callback = None
    elif callable(progress):
        callback = progress
    else:
        raise TypeError(f"progress must be a bool or a callable, got {type(progress).__name__}")
    if params is not None and not isinstance(params, LoopDetectorParams):
        if not isinstance(params, (str, bytes, _os.PathLike)):
            raise TypeError(
                "params must be a LoopDetectorParams, a parameter file or None, got "
                + type(params).__name__
            )
        params = _os.fsdecode(params)
    frames, used, similarity = _detect_loops(
        paths, vocabulary, descriptor, max_features, params, stride, max_width, video_fps,
        callback, online, resume_state or "", save_state or "", bool(skip_unreadable),
        threads,
    )
    for frame in frames:
        if frame.unreadable:
            _warnings.warn(f"{frame.file}: {frame.unreadable}; skipped", stacklevel=2)
    if printer is not None:
        printer.finish()
    results = LoopResults(frames)
    results.params = used
    results.similarity = similarity if similarity.frames else None
    results.descriptor = name
    results.vocabulary = "online" if online else vocabulary
    results.vocabulary_file = vocabulary_file
    results.inputs = [_os.path.normpath(_os.path.abspath(path)) for path in paths]
    if resume_state is not None:
        results.resumed_from = _os.path.normpath(_os.path.abspath(resume_state))
        results.resumed_frames = resumed_frames
    return results


def _resume(path, vocabulary, descriptor, params):
    """detect_loops' arguments resolved against the state saved at path:
    (path, its frames, vocabulary, descriptor)."""
    path = _path("resume_state", path)
    online, saved_descriptor, frames = _saved_state(path)
    if params is not None:
        raise ValueError(f"resume_state {path} keeps its own parameters; params must be None")
    wants_online = isinstance(vocabulary, str) and vocabulary == "online"
    if online and vocabulary is not None and not wants_online:
        raise ValueError(
            f"resume_state {path} holds an online vocabulary's state; vocabulary must be "
            'None or "online"'
        )
    if not online and wants_online:
        raise ValueError(
            f"resume_state {path} holds a fixed vocabulary's state; give the Vocabulary it "
            'was run with (or None for its descriptor\'s default), not "online"'
        )
    if saved_descriptor:
        name = descriptor.descriptor if isinstance(descriptor, FeatureExtractor) else descriptor
        if name is not None and name != saved_descriptor:
            raise ValueError(
                f"resume_state {path} was run with {saved_descriptor} descriptors, "
                f"not {name}"
            )
        if descriptor is None:
            descriptor = saved_descriptor
    return path, frames, "online" if online else vocabulary, descriptor


def _path(keyword, path):
    """The path argument `keyword` as a str (TypeError for anything else)."""
    if not isinstance(path, (str, bytes, _os.PathLike)):
        raise TypeError(f"{keyword} must be a path, got {type(path).__name__}")
    return _os.fsdecode(path)


class LoopResults(list):
    """What detect_loops returns: a list of LoopResult, one per frame, with
    what the run used, which write_report shows as the CLI's report does.

    params: the LoopDetectorParams of the run (after a video's frame rate and
    a parameter file); descriptor: the extractor's name; vocabulary: the
    Vocabulary; vocabulary_file: its file when detect_loops loaded the default
    one, else None; inputs: the inputs as absolute paths; similarity: the
    SimilarityMatrix of the run (None when the geometric check is "none": the
    detector then keeps no features to score); resumed_from and resumed_frames:
    the state a run resumed (resume_state, as an absolute path) and its frames,
    else None and 0.
    """

    params = None
    similarity = None
    descriptor = ""
    vocabulary = None
    vocabulary_file = None
    inputs = ()
    resumed_from = None
    resumed_frames = 0


def write_report(folder, results, ground_truth=None):
    """Write the HTML report of a run into folder (folder/index.html, the
    page of the CLI's detect-loops --report) and return the page's path.

    results: the LoopResults of detect_loops (whose frames know their files:
    each loop is drawn with its two images and inliers), or any list of
    LoopResult. ground_truth: a GroundTruth, to show each detection's verdict,
    precision and recall (as evaluate --report). Written atomically; OSError
    naming the folder when it cannot be.
    """
    run = results if isinstance(results, LoopResults) else LoopResults()
    inputs = ""
    if run.inputs:
        inputs = run.inputs[0] + (" ..." if len(run.inputs) > 1 else "")
    vocabulary = run.vocabulary_file or (
        "online" if isinstance(run.vocabulary, str) else repr(run.vocabulary) if run.vocabulary else ""
    )
    return _write_report(
        _os.fsdecode(folder), results, ground_truth, run.params, inputs, vocabulary,
        run.descriptor, run.similarity,
    )
