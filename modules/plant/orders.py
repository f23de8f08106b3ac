"""A run that ends with its orders: `run.orders` bottles taken out by the plant's sinks."""
from __future__ import annotations

from hub.core.observer import Stop
from modules.sink import Bin


class Orders:
    """Counts the bottles the sinks took (delivered, rightly or not) against the number wanted: a
    stop condition (hub/core/observer.py) that sinks contribute (Module.CONTRIBUTES)."""

    def __init__(self, plant, wanted: int):
        self.wanted = wanted
        self.rate = plant.scenario.run.physics_rate
        self.bins = [c for c in plant.components if isinstance(c, Bin)]

    @classmethod
    def for_plant(cls, plant) -> Orders | None:
        wanted = plant.scenario.run.orders
        return None if wanted is None else cls(plant, wanted)

    @property
    def delivered(self) -> int:
        return sum(len(b.deliveries) for b in self.bins)

    def done(self) -> bool:
        return self.delivered >= self.wanted

    def stop(self, tick: int) -> Stop | None:
        if not self.done():
            return None
        return Stop(f"{self.wanted} orders delivered at t = {tick / self.rate:.9g} s (run.orders)", ended=True)
