"""The bottling plant's routing as a PLC program would run it, on the tag table `planthub gateway
--export-tags` writes: at each new scan, for each reader whose event counter moved, pulse the
switch's command into its lane (or back to base) for one scan; then write the scan back.
The same decisions as modules/plant_control.py, on tags instead of slots."""
from __future__ import annotations

import argparse
import csv


def read_tags(path) -> dict:
    with open(path, newline="") as f:
        return {row["tag"]: row for row in csv.DictReader(f)}


class Routing:
    def __init__(self, lanes: list[str]):
        self.lanes = lanes
        self.seen = [0] * len(lanes)
        self.decisions = 0

    def scan(self, counts: list[int], destinations: list[str]) -> dict:
        """The command bits of this scan (every one of them: a bit not set now is cleared)."""
        bits = {}
        for i, lane in enumerate(self.lanes, start=1):
            moved = counts[i - 1] != self.seen[i - 1]
            self.seen[i - 1] = counts[i - 1]
            ours = destinations[i - 1] == lane
            bits[f"sw{i}_work"] = moved and ours
            bits[f"sw{i}_base"] = moved and not ours
            self.decisions += moved
        return bits


def arguments(doc: str) -> argparse.Namespace:
    """A test PLC's command line: TAGS.csv ENDPOINT --lanes A,B,… [--limit S]."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("tags")
    parser.add_argument("endpoint")
    parser.add_argument("--lanes", required=True)
    parser.add_argument("--limit", type=float, default=300.0)
    return parser.parse_args()
