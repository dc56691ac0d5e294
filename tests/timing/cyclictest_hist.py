"""Summary of a cyclictest histogram file (cyclictest -h N -q > FILE), shared by the timing
scripts: wake-up latency p50/p99/max in microseconds and how many wake-ups came a whole
period (or more) late. None when the file holds no histogram (cyclictest failed)."""


def summary(path, period_us):
    hist, overflow, mx = {}, 0, None
    for line in open(path):
        p = line.split()
        if len(p) == 2 and p[0].isdigit() and p[1].isdigit():
            hist[int(p[0])] = int(p[1])
        if line.startswith('# Histogram Overflows'):
            overflow = int(line.split()[-1])
        if line.startswith('# Max Latencies'):
            mx = int(line.split()[-1])
    n = sum(hist.values()) + overflow
    if n == 0 or mx is None:
        return None

    def pct(q):
        rank, seen = q / 100 * n, 0
        for us in sorted(hist):
            seen += hist[us]
            if seen >= rank:
                return us
        return mx

    return {"count": n, "p50_us": pct(50), "p99_us": pct(99), "max_us": mx,
            "over_period": sum(c for us, c in hist.items() if us >= period_us) + overflow}


def bins(path):
    """The histogram's non-empty bins {us: count} (cyclictest -h N -q > FILE), and the
    overflow count: ({}, 0) when the file holds no histogram."""
    hist, overflow = {}, 0
    for line in open(path):
        p = line.split()
        if len(p) == 2 and p[0].isdigit() and p[1].isdigit() and int(p[1]) > 0:
            hist[int(p[0])] = int(p[1])
        if line.startswith('# Histogram Overflows'):
            overflow = int(line.split()[-1])
    return hist, overflow
