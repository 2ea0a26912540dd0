#!/usr/bin/env python3
"""Detect loops in a folder of images and plot the similarity matrix.

    python3 detect_and_plot.py data/samples/rtabmap/samples \\
        --gt data/samples/rtabmap/samples_GT_pairs.txt -o similarity.png

Loops are found by binbow.detect_loops (the same loops as `binbow detect-loops`).
The picture is the matrix of bag-of-words similarities of every image (rows,
the query) with every earlier image (columns) that detect_loops returns with
its results (results.similarity; long runs binned to at most 1000 x 1000 cells). Ground-truth loops (--gt: an image matrix,
a MATLAB .mat or text pairs) are outlined, and each detection is marked: green
when the ground truth confirms it, red when it does not, white without --gt.

Needs Debian's python3-matplotlib and python3-numpy; writes a PNG without a
display (Agg). Folders, lists and videos alike.
"""
import argparse
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)
import numpy as np  # noqa: E402

import binbow  # noqa: E402


def similarity_scores(similarity):
    """The run's matrix with the cells that hold no pair of an image with an earlier one as NaN.

    Above the diagonal there is no earlier image; on it neither, unless a cell
    bins several frames: an unbinned diagonal of zeros would draw as a black
    line through the plot.
    """
    scores = similarity.scores.copy()
    first_masked = 0 if similarity.bin == 1 else 1
    scores[np.triu_indices(similarity.cells, k=first_masked)] = np.nan
    return scores


def plot(similarity, scoring, results, truth, evaluation, output, title):
    scores = similarity_scores(similarity)
    figure, axes = plt.subplots(figsize=(8, 7), dpi=120)
    finite = scores[np.isfinite(scores)]
    top = np.percentile(finite, 99.5) if finite.size else 1.0
    # Axes in frame indices also when long runs are binned (bin frames a cell).
    side = similarity.cells * similarity.bin
    shown = axes.imshow(scores, cmap="magma", vmin=0, vmax=top or 1.0, interpolation="nearest",
                        extent=(-0.5, side - 0.5, side - 0.5, -0.5))
    figure.colorbar(shown, ax=axes, fraction=0.046, pad=0.04, label=f"similarity ({scoring} score)")

    if truth is not None:
        pairs = [(j, i) for i in range(min(truth.frames, similarity.frames))
                 for j in truth.earlier_matches(i)]
        if pairs:
            x, y = zip(*pairs)
            axes.scatter(x, y, s=22, marker="s", facecolors="none", edgecolors="#4fc3f7",
                         linewidths=0.8, label="ground truth")

    loops = [r for r in results if r.detection]
    if evaluation is not None:
        for correct, colour, name in ((True, "#00e676", "detection (true)"),
                                      (False, "#ff1744", "detection (false)")):
            points = [(m, q) for q, m, verdict in evaluation.verdicts if verdict == correct]
            if points:
                x, y = zip(*points)
                axes.scatter(x, y, s=30, marker="x", color=colour, linewidths=1.5, label=name)
    elif loops:
        axes.scatter([r.match for r in loops], [r.query for r in loops], s=30, marker="x",
                     color="white", linewidths=1.5, label="detection")

    axes.set_xlabel("earlier image (0-based index)")
    axes.set_ylabel("query image (0-based index)")
    axes.set_title(title, fontsize=10)
    if axes.get_legend_handles_labels()[0]:
        axes.legend(loc="upper right", fontsize=8, framealpha=0.8)
    figure.tight_layout()
    figure.savefig(output)
    plt.close(figure)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("inputs", nargs="+", help="folders, image files or text lists of images")
    parser.add_argument("--gt", help="ground truth: image matrix, .mat or text pairs")
    parser.add_argument("--gt-base", type=int, choices=(0, 1), help="index base of text pairs")
    parser.add_argument("--vocab", help="vocabulary file (default: the bundled one)")
    parser.add_argument("--descriptor", default="orb", choices=("orb", "brief", "akaze", "brisk"))
    parser.add_argument("--params", help="loop detector parameters, JSON or YAML")
    parser.add_argument("-o", "--output", default="similarity.png", help="PNG to write")
    arguments = parser.parse_args(argv)

    vocabulary = (binbow.Vocabulary.load(arguments.vocab) if arguments.vocab
                  else binbow.Vocabulary.default(arguments.descriptor))
    params = binbow.LoopDetectorParams.from_file(arguments.params) if arguments.params else None
    results = binbow.detect_loops(arguments.inputs, vocabulary=vocabulary,
                                  descriptor=arguments.descriptor, params=params, progress=True)
    if results.similarity is None:
        raise ValueError('no similarity matrix: the parameters say "geometric_check": "none"')

    truth = evaluation = None
    title = f"{len(results)} images, {sum(r.detection for r in results)} loops detected"
    if arguments.gt:
        truth = binbow.GroundTruth.load(arguments.gt, base=arguments.gt_base, frames=len(results))
        evaluation = binbow.evaluate(results, truth)
        title += f"; precision {evaluation.precision:.3f}, recall {evaluation.recall:.3f}"
    plot(results.similarity, vocabulary.scoring, results, truth, evaluation, arguments.output, title)
    print(title)
    print(f"wrote {arguments.output}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except (OSError, ValueError, binbow.Error) as error:
        sys.exit(f"detect_and_plot.py: error: {error}")
