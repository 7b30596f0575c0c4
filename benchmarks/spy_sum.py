"""Spy sum: where a command's threads work, from a py-spy record; what the main thread does itself
is what a host of many cores waits on.

    py-spy record -r 100 --threads --format raw -o record.txt -- blueprint render MODEL -o out.svg
    python benchmarks/spy_sum.py record.txt [--rate 100] [--top 40]

py-spy (not a dependency of the package; ``pip install py-spy``) samples every thread ``--rate``
times a second, leaving out idle samples, and writes one line a distinct stack with its count.
This prints, in seconds (samples over the rate): the main thread's and the other threads' work;
the main thread's by ``blueprint`` function, inclusive (every function on the stack); the main
thread's and the other threads' by their innermost ``blueprint`` function and the function it
was in (a NumPy call shows as the line that made it).
"""

from __future__ import annotations

import argparse
import re
from collections import Counter
from pathlib import Path

_FRAME = re.compile(r"(.*) \((.*?):\d+\)$")


def summed(path: Path) -> tuple[Counter, Counter, Counter, int, int]:
    """The main thread's samples by function (inclusive) and by innermost function, the other
    threads' by innermost function, and the two totals."""
    inclusive, main_inner, other_inner = Counter(), Counter(), Counter()
    main_total = other_total = 0
    for line in path.read_text().splitlines():
        stack, _, count = line.rpartition(" ")
        thread, _, frames = stack.partition(";")
        named = [m.groups() for m in map(_FRAME.match, frames.split(";")) if m]
        ours = [f"{name} ({file})" for name, file in named if file.startswith("blueprint/")]
        inner = f"{ours[-1] if ours else '?'} > {named[-1][0] if named else '?'}"
        n = int(count)
        if "MainThread" in thread:
            main_total += n
            inclusive.update({function: n for function in set(ours)})
            main_inner[inner] += n
        else:
            other_total += n
            other_inner[inner] += n
    return inclusive, main_inner, other_inner, main_total, other_total


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("record", type=Path, help="py-spy's raw record (--format raw)")
    parser.add_argument("--rate", type=float, default=100.0, help="the samples a second it was taken at")
    parser.add_argument("--top", type=int, default=40)
    args = parser.parse_args()
    inclusive, main_inner, other_inner, main_total, other_total = summed(args.record)
    print(f"main thread {main_total / args.rate:.2f} s, other threads {other_total / args.rate:.2f} s")
    for title, counts in (
        ("main thread, inclusive", inclusive),
        ("main thread, innermost", main_inner),
        ("other threads, innermost", other_inner),
    ):
        print(f"-- {title}")
        for function, count in counts.most_common(args.top):
            print(f"{count / args.rate:8.2f} s  {function}")


if __name__ == "__main__":
    main()
