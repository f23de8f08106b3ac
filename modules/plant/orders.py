"""A run that ends with its orders: `run.orders` bottles taken out by the plant's sinks."""
from __future__ import annotations

from modules.sink import Bin


class Orders:
    """Counts the bottles the sinks took (delivered, rightly or not) against the number wanted."""

    def __init__(self, plant, wanted: int):
        self.wanted = wanted
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

    def reason(self, seconds: float) -> str:
        return f"{self.wanted} orders delivered at t = {seconds:.9g} s (run.orders)"
