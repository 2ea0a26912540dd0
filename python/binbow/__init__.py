"""Bags of binary words for fast place recognition (Galvez-Lopez & Tardos 2012).

Descriptors are numpy uint8 arrays of shape (n, code_size), one row per
feature, as OpenCV's ORB and BRIEF return them; None (what OpenCV returns for
an image without keypoints) is an image with no features.
"""

import os as _os

from . import _data_location
from ._binbow import (
    BowVector,
    BuildProgress,
    Database,
    Error,
    Evaluation,
    FeatureExtractor,
    GroundTruth,
    LoopDetector,
    LoopDetectorParams,
    LoopResult,
    Vocabulary,
    __version__,
    evaluate,
    hamming,
)

__all__ = [
    "BowVector",
    "BuildProgress",
    "Database",
    "Error",
    "Evaluation",
    "FeatureExtractor",
    "GroundTruth",
    "LoopDetector",
    "LoopDetectorParams",
    "LoopResult",
    "Vocabulary",
    "data_directories",
    "evaluate",
    "hamming",
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


def _default_vocabulary(descriptor="orb"):
    """The bundled default vocabulary of "orb" or "brief" descriptors.

    Searched in vocab/ of each of data_directories(); FileNotFoundError names
    the places searched when it is not installed.
    """
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
            return Vocabulary.load(path)
    raise FileNotFoundError(
        f"the default {descriptor} vocabulary is not installed; set BINBOW_DATA_DIR to binbow's "
        "data folder (the repository's data/). Searched: " + ", ".join(candidates)
    )


Vocabulary.default = staticmethod(_default_vocabulary)
