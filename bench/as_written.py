"""What the readers make of the public corpus, without a render: per file kind, how many materials are
read exactly, how many are rendered as their file holds them (`Material.native`, by why: no reading,
a reading that leaves something out, textured), and how many are refused, by reason (what no renderer
here renders).

    python bench/as_written.py [FOLDER ...]     (default: ../shared/corpus/mitsuba-data, ../shared/corpus/materialx)
"""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path

from common import ROOT

from brdfremap.core.library.formats import collect_formats

CORPUS = ROOT.parent / "shared" / "corpus"


def main(argv: list[str]) -> int:
    folders = [Path(a) for a in argv] or [CORPUS / "mitsuba-data", CORPUS / "materialx"]
    formats = collect_formats()
    for folder in folders:
        kinds: Counter[str] = Counter()
        refused: Counter[str] = Counter()
        for path in sorted(p for p in folder.rglob("*") if p.is_file()):
            reader = formats.reader_for(path)
            if reader is None:
                continue
            try:
                entries = reader.read(path)
            except Exception as exc:  # noqa: BLE001 - a file the reader refuses is counted, not fatal
                refused[f"file not read: {str(exc).splitlines()[0][:70]}"] += 1
                continue
            for e in entries:
                m = e.material
                if e.problem:
                    refused[e.problem.split(":")[0][:70]] += 1
                elif m.native is None:
                    kinds["read exactly"] += 1
                elif not m.model:
                    kinds["as written, no reading"] += 1
                elif m.native.driven:
                    kinds["as written, textured (reading: the images' means)"] += 1
                else:
                    kinds["as written, a reading that leaves something out"] += 1
        total = sum(kinds.values()) + sum(refused.values())
        print(f"## {folder} ({total} materials)\n")
        for k, n in kinds.most_common():
            print(f"- {k}: {n}")
        print(f"- refused: {sum(refused.values())}")
        for k, n in refused.most_common():
            print(f"  - {k}: {n}")
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
