"""Where one `head` update spends its time: the share of `perf` samples per part of the update.

Record a case of the `head_cases` bench with call stacks, then read them:

    cargo bench -p trackers --bench head_cases --no-run
    BENCH=$(ls -t target/release/deps/head_cases-* | grep -v '\\.d$' | head -1)
    RAYON_NUM_THREADS=1 perf record -F 999 --call-graph dwarf,16384 -o case.data \\
        $BENCH --bench --profile-time 4 640x360_target_67x78_locked
    perf script -i case.data > case.script
    python3 crates/trackers/benches/head_cases_profile.py case.script [more.script ...]

Only samples inside the tracker's update count. Each is put in the first part, in the order of
PARTS, one of whose functions is on its stack (so the cold start's search is not counted again
among the Gauss-Newton fits that contain it); the rest is bookkeeping. Prints a Markdown table,
one column per script.
"""

import sys
from collections import Counter

UPDATE = ("ScaledTracker as trackers::api::Tracker>::update",
          "ParticleTracker as trackers::api::Tracker>::update")

PARTS = [
    ("motion: cold start's search", ["best_start"]),
    ("motion: pyramids", ["MotionFrames::advance", "MotionFrames::build", "MotionFrames::start"]),
    ("motion: test on the frame's pixels", ["test_at_frame_resolution"]),
    ("motion: Gauss-Newton fits", ["MotionStage::estimate"]),
    ("shrinking to the working scale", ["Shrinker::"]),
    ("detection and reacquisition", ["Appearance::detect", "reacquisition"]),
    ("appearance terms (likelihood)", ["log_likelihood_batch"]),
    ("appearance models (read, learn)", ["Appearance::"]),
    ("resampling", ["resample"]),
]
REST = "bookkeeping (proposal draws, estimates, lock chain)"


def stacks(path):
    """The call stacks of a `perf script` output: one list of frame names per sample."""
    sample = []
    with open(path) as f:
        for line in f:
            line = line.rstrip()
            if not line:
                if sample:
                    yield sample
                sample = []
            elif line[0] in " \t":
                parts = line.split(None, 1)
                if len(parts) == 2:
                    sample.append(parts[1])
    if sample:
        yield sample


def shares(path):
    counts, total = Counter(), 0
    for stack in stacks(path):
        if not any(u in f for f in stack for u in UPDATE):
            continue
        total += 1
        part = next((name for name, fns in PARTS if any(g in f for f in stack for g in fns)), REST)
        counts[part] += 1
    if total == 0:
        sys.exit(f"{path}: no sample inside a tracker update")
    return {name: counts[name] / total for name, _ in PARTS + [(REST, None)]}


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    columns = [(p, shares(p)) for p in sys.argv[1:]]
    print("| part | " + " | ".join(p for p, _ in columns) + " |")
    print("|---" * (len(columns) + 1) + "|")
    for name, _ in PARTS + [(REST, None)]:
        print(f"| {name} | " + " | ".join(f"{100 * s[name]:.0f} %" for _, s in columns) + " |")


main()
