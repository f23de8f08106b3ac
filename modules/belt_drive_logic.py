"""Belt drive logic as a bus participant: ramps the belt speed towards its setpoint while `run` is true."""
from hub.participant import Participant, serve


class BeltDrive(Participant):
    inputs = {"run": "bool", "speed_setpoint": "real"}
    outputs = {"speed": "real", "running": "bool"}
    parameters = {"ramp": 0.5}   # m/s²; the scenario's value arrives with the hub's welcome

    def step(self, t, h):
        target = self.speed_setpoint if self.run else 0.0
        gap, most = target - self.speed, self.ramp * h
        if gap != 0.0:   # the arithmetic of fmus/models/belt_drive, in its order: equal doubles
            if self.ramp == 0.0 or abs(gap) <= most * (1.0 + 1e-9):
                self.speed = target
            else:
                self.speed += most if gap > 0 else -most
        self.running = self.speed != 0.0


if __name__ == "__main__":
    raise SystemExit(serve(BeltDrive()))
