"""Plant management (the paper's PLC/MES role) as a bus participant: routes each bottle by its id.

Each of the plant's three track switches has an ID reader just before it. When a reader reads
a bottle, the destination looked up for its id (the reader's `destination` slot) decides: the
switch turns into its lane (MoveToWorkingPos) if the bottle is for that lane, and back to base
position (MoveToBasePos) otherwise. `lanes` lists the destination of each switch's branch, in
order; its default is the bottling plant's. Run by the hub (`command:` in the scenario) or
joined from anywhere with `python -m modules.plant_control --run RUN --name NAME --connect ...`.
"""
from hub.participant import Participant, serve

SWITCHES = 3


class PlantControl(Participant):
    inputs = {**{f"r{i}_read": "void" for i in range(1, SWITCHES + 1)},
              **{f"r{i}_destination": "string" for i in range(1, SWITCHES + 1)}}
    outputs = {**{f"sw{i}_work": "void" for i in range(1, SWITCHES + 1)},
               **{f"sw{i}_base": "void" for i in range(1, SWITCHES + 1)}}
    parameters = {"lanes": "A,B,C"}   # destination of switch i's branch, comma-separated

    def step(self, t, h):
        lanes = self.lanes.split(",")
        for i in range(1, SWITCHES + 1):
            read = getattr(self, f"r{i}_read")
            ours = read and getattr(self, f"r{i}_destination") == lanes[i - 1]
            setattr(self, f"sw{i}_work", bool(ours))
            setattr(self, f"sw{i}_base", bool(read and not ours))


if __name__ == "__main__":
    raise SystemExit(serve(PlantControl()))
