"""The longest run of frames on which a tracker's box is too large: wider or taller than
THRESHOLD times the labelled box (default 1.2), per sequence, from the boxes `track eval otb`
writes (OUT/ope/TRACKER/SEQ.txt) and each sequence's `groundtruth_rect.txt`.

    python3 xtask/scripts/box_size_runs.py OUT TRACKER SEQUENCE_DIR... [--threshold 1.2]

Frames whose label is missing, NaN or empty do not end a run and do not count in it. Prints one
Markdown row per OUT: the longest run on each sequence.
"""

import math
import re
import sys
from pathlib import Path


def boxes(path):
    """One [x, y, w, h] per line, or None where the line holds no four finite numbers."""
    out = []
    for line in Path(path).read_text().splitlines():
        values = [float(v) for v in re.split(r"[,\s]+", line.strip()) if v]
        ok = len(values) == 4 and all(math.isfinite(v) for v in values)
        out.append(values if ok else None)
    return out


def longest_run(tracked, truth, threshold):
    """The most consecutive labelled frames whose box exceeds the label's width or height by
    more than `threshold` times."""
    run = best = 0
    for box, label in zip(tracked, truth):
        if box is None or label is None or label[2] <= 0 or label[3] <= 0:
            continue
        if max(box[2] / label[2], box[3] / label[3]) > threshold:
            run += 1
            best = max(best, run)
        else:
            run = 0
    return best


def main(argv):
    threshold = 1.2
    if "--threshold" in argv:
        i = argv.index("--threshold")
        threshold = float(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if len(argv) < 3:
        sys.exit(__doc__)
    out, tracker, sequences = Path(argv[0]), argv[1], [Path(s) for s in argv[2:]]
    runs = []
    for seq in sequences:
        tracked = boxes(out / "ope" / tracker / f"{seq.name}.txt")
        runs.append(longest_run(tracked, boxes(seq / "groundtruth_rect.txt"), threshold))
    print("| " + " | ".join(s.name for s in sequences) + " |")
    print("|" + "---|" * len(sequences))
    print("| " + " | ".join(str(r) for r in runs) + " |")


if __name__ == "__main__":
    main(sys.argv[1:])
