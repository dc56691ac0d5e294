#!/usr/bin/env python3
"""The summaries (one entry per cell: scores, collisions, perception's accuracy) of several
`staa-sim experiment` results.json files, as one JSON list: docs/results/perception/summary.json.

usage: summary.py OUT.json RESULTS.json [RESULTS.json ...]"""
import json
import sys

cells = []
for path in sys.argv[2:]:
    cells += json.load(open(path))['summary']
json.dump(cells, open(sys.argv[1], 'w'), indent=1)
