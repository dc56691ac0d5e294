#!/usr/bin/env python3
"""STAA*'s score with ground truth, the truth within each agent's line of sight (sight), the
head camera (depth) and the camera with the base scanner (depth+scan), per map, mode and agent
count: docs/results/perception/scores.svg.

usage: figure.py OUT.svg SUMMARY.json  (SUMMARY.json: summary.py's output)
Each bar is the mean score of 5 runs, its whisker one standard deviation; the number above
it is the runs' collisions (of all agents, each agent of a pair counted)."""
import json
import sys

SOURCES = [('truth', '#2a9d6a', 'ground truth'), ('sight', '#9bc9a0', 'truth in line of sight'),
           ('depth', '#e08a2c', 'camera (depth)'), ('depth+scan', '#5b7fc7', 'camera + scanner (depth+scan)')]
MAPS = ['office', 'apartment', 'clutter', 'depot']
MODES = ['cooperative', 'ghost']


def main(out, summary_path):
    cells = json.load(open(summary_path))
    get = {(c['map'], c['mode'], c['agents'], c['obstacles']): c for c in cells if c['controller'] == 'staa'}
    agents = sorted({c['agents'] for c in cells})
    groups = [(m, mode) for mode in MODES for m in MAPS]
    bar, gap, left, top, row_h, plot_h = 18, 26, 90, 50, 230, 170
    group_w = len(SOURCES) * bar + gap
    width = left + len(groups) * group_w + 20
    height = top + len(agents) * row_h + 30
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" font-size="11">',
           f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="{left}" y="18" font-size="14">STAA*: score per 60 s run (mean, one standard deviation; collisions above)</text>']
    for k, (_, colour, label) in enumerate(SOURCES):
        x = left + k * 195
        svg.append(f'<rect x="{x}" y="28" width="12" height="12" fill="{colour}"/><text x="{x + 16}" y="38">{label}</text>')
    for r, n in enumerate(agents):
        y0 = top + r * row_h + 10
        row = [get.get((m, mode, n, s)) for (m, mode) in groups for s, _, _ in SOURCES]
        high = max([c['score']['mean'] + c['score']['stddev'] for c in row if c] + [1.0])
        scale = plot_h / high
        base = y0 + plot_h
        svg.append(f'<text x="8" y="{y0 + plot_h / 2}">{n} agent{"s" if n > 1 else ""}</text>')
        svg.append(f'<line x1="{left}" y1="{base}" x2="{width - 20}" y2="{base}" stroke="#444"/>')
        step = 2 if high <= 12 else 5 if high <= 30 else 10
        for t in range(0, int(high) + 1, step):
            ty = base - t * scale
            svg.append(f'<line x1="{left - 4}" y1="{ty:.1f}" x2="{width - 20}" y2="{ty:.1f}" stroke="#ddd"/>')
            svg.append(f'<text x="{left - 7}" y="{ty + 4:.1f}" text-anchor="end" fill="#444">{t}</text>')
        for g, (m, mode) in enumerate(groups):
            gx = left + g * group_w
            for k, (s, colour, _) in enumerate(SOURCES):
                c = get.get((m, mode, n, s))
                if not c:
                    continue
                mean, sd = c['score']['mean'], c['score']['stddev']
                collisions = round(c['collisions']['mean'] * c['runs'])
                h = max(0.0, mean) * scale
                x = gx + k * bar
                svg.append(f'<rect x="{x}" y="{base - h:.1f}" width="{bar - 2}" height="{h:.1f}" fill="{colour}"/>')
                y1, y2 = base - max(0.0, mean - sd) * scale, base - (mean + sd) * scale
                svg.append(f'<line x1="{x + bar / 2 - 1}" y1="{y1:.1f}" x2="{x + bar / 2 - 1}" y2="{y2:.1f}" stroke="#222"/>')
                svg.append(f'<text x="{x + bar / 2 - 1}" y="{y2 - 3:.1f}" font-size="8" text-anchor="middle">{collisions}</text>')
            if r == len(agents) - 1:
                svg.append(f'<text x="{gx + len(SOURCES) * bar / 2}" y="{base + 14}" text-anchor="middle">{m}</text>')
                svg.append(f'<text x="{gx + len(SOURCES) * bar / 2}" y="{base + 26}" text-anchor="middle" fill="#666">{mode}</text>')
    svg.append('</svg>')
    open(out, 'w').write('\n'.join(svg) + '\n')


if __name__ == '__main__':
    main(sys.argv[1], sys.argv[2])
