"""Markdown tables from the JSON lines the benchmarks print.

python benchmarks/summary.py results/*.jsonl
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict
from pathlib import Path


def main() -> None:
    rows_by_file: dict[str, list[dict]] = defaultdict(list)
    for name in sys.argv[1:]:
        for line in Path(name).read_text().splitlines():
            if line.startswith("{"):
                rows_by_file[Path(name).stem].append(json.loads(line))
    for stem, rows in rows_by_file.items():
        keys = [k for k in rows[0] if k not in ("renderer", "stages", "ms_min", "ms_max")]
        print(f"\n### {stem} ({rows[0].get('renderer', '?')})\n")
        print("| " + " | ".join(keys) + " |")
        print("|" + "---|" * len(keys))
        for row in rows:
            print("| " + " | ".join(str(row.get(k, "")) for k in keys) + " |")


if __name__ == "__main__":
    main()
