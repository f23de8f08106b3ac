"""Benchmark viewer: watches every slot of a run (at PERIOD s, if given) until the run stops, then prints
how many samples it got."""
import sys

from hub.live import Viewer

if __name__ == "__main__":
    run, endpoint = sys.argv[1], sys.argv[2]
    period = float(sys.argv[3]) if len(sys.argv) > 3 else None
    count = 0
    with Viewer(run, [endpoint]) as viewer:
        viewer.watch("**", period)
        while viewer.next(5.0) is not None:
            count += 1
    print(count)
