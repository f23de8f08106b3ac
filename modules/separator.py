"""Separator: two gates a bottle's length apart, closed alternately, let one bottle through per cycle (the paper's Fig. 9).

Base position: BP closed, WP open — the queue runs up to BP. Working position: WP closes
between the first and the second bottle, then BP opens and lets that one bottle go. Back to
base: BP closes, WP opens, the next bottle moves up. Which gate moves when is the separator's
state logic: with `logic: default` the paper's net runs as the object's `logic` component,
driven by the sensors around it (B326 at BP, B327 behind it, B321 downstream); without it,
flows drive the gates directly. See modules/gate.py for the timing of one gate.

WP stands where the second bottle of a queue held by BP begins, so closing it always meets
that bottle's front: a gate could never wait for a gap in a queue of touching bottles. So WP,
unlike every other gate, may close onto a bottle reaching up to `push` into it, and the
engine pushes that bottle (and the queue behind it) back by that much. Measured with a 5 mm
gate at 0.5 m/s, 150 Hz: switching on at up to 25 mm of overlap pushes the bottle back at
under the belt speed and tilts it by under 1°; at 30 mm (its axis at the gate) it is pushed
through. The bottles must come in single file: a lane a little wider than a bottle (in a
10 cm lane 6 cm bottles queue zig-zag, side by side).

Physics rate: the separator works at the paper's 150 Hz with a queue of any length pressed
against BP, because bottles touch at their contact ring, through their centre of mass
(hub/physics/world.py), and the belt's `friction` bounds how hard a held queue is pushed
(μ·m·g per bottle; the field's law alone, k = 16/s at 0.5 m/s, pushes at 0.8 g). Measured, a queue
pressed against a stopper at 150 Hz, μ = 0.2 (`python -m tests.bench_queue`): 12 bottles, the
first 0.01 mm into the gate, neighbours 0.3 mm into each other, tilt under 1°; 40 bottles,
1.2 mm and 0.8°. With plain cylinders (as one-link multibodies, 50 solver iterations) the
first bottle sank 25 mm into the gate and 15-20 mm into the floor and WP could not close
between two bottles, so this needed 500 Hz. Guard
rails must reach above the contact ring (the conveyor's default `rail_height`, 7 cm, does
for a 10 cm bottle): over a lower rail a zig-zag queue leans and tips.
scenarios/separator.yaml and separator_logic.yaml let eight queued bottles through at 150 Hz,
one per cycle.

The gates are interlocked, as a separator's mechanics keeps them: a gate opens only while the
other is closed, so at least one always holds the queue. A logic that moves both at once (the
separator Petri net sets BasePos and WorkingPos in one step) thus gets WP closed before BP
opens and BP closed before WP opens, and never lets two bottles through.
"""
from __future__ import annotations

import math

from hub.core.logic_spec import LogicSpec
from hub.core.module import Module
from modules.gate import GATE_PARAMETERS, Gate, along, gate_across
from modules.params import POSITION, YAW


def pitch(params) -> float:
    """Distance between the gates' centres: the first bottle of the queue fits between them."""
    return params["thickness"] + params["bottle_diameter"]


class Separator(Module):
    """BP stands at `position` (on the belt's centre line, at its surface), WP one bottle upstream of it."""

    PARAMETERS = {
        "type": "object",
        "properties": {
            "position": {**POSITION, "description": "foot of the downstream gate BP on the belt's centre line, m"},
            "yaw": {**YAW, "description": "heading of the belt there, degrees"},
            "bottle_diameter": {"type": "number", "exclusiveMinimum": 0, "default": 0.06,
                                "description": "diameter of the bottles it separates, m: sets the gates' pitch"},
            **GATE_PARAMETERS,
            "push": {"type": "number", "minimum": 0, "default": 0.015,
                     "description": "how deep the second bottle may reach into WP when it closes, m (it is pushed back)"},
            "working": {"type": "boolean", "default": False,
                        "description": "start in working position (WP closed, BP open) instead of base position"},
        },
        "required": ["position"],
        "additionalProperties": False,
    }
    COMPONENTS = {"bp": Gate, "wp": Gate}
    # The paper's Fig. 10 net (fmus/nets/separator.net.yaml): feed the sensors' on_stay to
    # logic.B326_put, logic.B327_put and logic.B321_put; its BasePos and WorkingPos places
    # close BP and WP.
    LOGIC = LogicSpec(
        model="separator",
        events=("B326_put", "B327_put", "B321_put"),
        wiring=(("logic.BasePos_marked", "bp.closed"), ("logic.WorkingPos_marked", "wp.closed")),
    )

    @classmethod
    def check(cls, params):
        if params["push"] < params["thickness"]:
            return [(("push",), f"{params['push']:g} m is less than WP's thickness ({params['thickness']:g} m): "
                                "the second bottle of a queue reaches that far into WP, so it could never close")]
        if params["push"] >= params["bottle_diameter"] / 2:
            return [(("push",), f"{params['push']:g} m reaches the axis of a bottle of diameter "
                                f"{params['bottle_diameter']:g} m: WP would push it through, not back "
                                f"(keep it below {params['bottle_diameter'] / 2:g} m)")]
        return []

    @classmethod
    def build(cls, name, params, world):
        yaw = math.radians(params["yaw"])
        working = params["working"]
        bp = gate_across(world, params["position"], yaw, params, not working)
        wp_at = along(params["position"], params["yaw"], -pitch(params))
        wp = gate_across(world, wp_at, yaw, params, working, params["push"])
        bp.interlock, wp.interlock = wp, bp
        return {"bp": Gate(name, "bp", bp), "wp": Gate(name, "wp", wp)}
