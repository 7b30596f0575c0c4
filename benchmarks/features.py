"""The extra cost of depth masking, highlighting, shaded parts and glyphs over a plain frame.

Prints one JSON object per case: median whole-frame milliseconds (image read back) after
warm-up, and the ratio to the plain frame of the same model and size.

    python benchmarks/features.py MODEL --highlight "Piston*" [--glyphs marks.toml] [--size 1024 1024]
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path

from blueprint import default_renderer, load_model, render_frame


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("model")
    parser.add_argument("--highlight", required=True, help="part pattern to highlight, reveal and shade")
    parser.add_argument("--glyphs", default=None, help="a glyph file (default: a box around the model)")
    parser.add_argument("--size", nargs=2, type=int, default=[1024, 1024])
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--warmup", type=int, default=3)
    args = parser.parse_args()
    model = load_model(args.model)
    renderer = default_renderer()
    size = tuple(args.size)
    lo, hi = model.bounds
    glyphs = args.glyphs or {"box": [{"min": lo.tolist(), "max": hi.tolist(), "label": "bounds"}]}
    if not isinstance(glyphs, str):
        from blueprint import Glyphs

        glyphs = Glyphs.from_dict(glyphs, source="generated")
    cases = {
        "plain": {},
        "highlight": {"highlight": args.highlight},
        "highlight+reveal 0.9": {"highlight": args.highlight, "reveal": 0.9},
        "shade": {"shade": args.highlight},
        "glyphs": {"glyphs": glyphs},
        "all": {"highlight": args.highlight, "reveal": 0.9, "shade": args.highlight, "glyphs": glyphs},
    }
    base = None
    for name, options in cases.items():
        for _ in range(args.warmup):
            render_frame(model, size=size, renderer=renderer, **options)
        frames = [render_frame(model, size=size, renderer=renderer, **options) for _ in range(args.frames)]
        ms = statistics.median(f.ms for f in frames)
        base = ms if base is None else base
        print(
            json.dumps(
                {
                    "renderer": renderer.info["renderer"],
                    "model": Path(args.model).name,
                    "triangles": model.triangle_count,
                    "width": size[0],
                    "height": size[1],
                    "case": name,
                    "layers": frames[-1].layers,
                    "ms": round(ms, 3),
                    "vs_plain": round(ms / base, 2),
                }
            ),
            flush=True,
        )


if __name__ == "__main__":
    main()
