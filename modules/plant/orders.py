"""A run that ends with its orders: `run.orders` bottles taken out by the plant's sinks."""
from __future__ import annotations

from dataclasses import dataclass

from hub.core.observer import Stop
from hub.scenario.expectations import Implied, Outcome
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

    # --- what `run.orders` promises: judged by `planthub test`, said in the summary -------------
    def outcome(self, tick: int) -> Outcome:
        """The implied expectation: the run ended with its orders delivered."""
        met = Implied(f"the run ends with its {self.wanted} orders delivered (run.orders)")
        if self.done():
            return Outcome(met, True, f"{self.delivered} delivered")
        return Outcome(met, False, f"the run ended at t = {tick / self.rate:.9g} s with {self.delivered} of "
                                   f"{self.wanted} orders delivered")

    def section(self) -> OrdersLine:
        return OrdersLine(self.wanted, self.delivered)


@dataclass(frozen=True)
class OrdersLine:
    """The summary's line for `run.orders` (a SummarySection, hub/core/observer.py)."""

    wanted: int
    delivered: int
    key = "orders"

    def lines(self) -> list[str]:
        if self.delivered >= self.wanted:
            return [f"  orders       {self.wanted} delivered (run.orders)"]
        return [f"  orders       {self.delivered} of {self.wanted} delivered: the run ended before its orders "
                f"(run.orders)"]

    def as_dict(self) -> dict:
        return {"wanted": self.wanted, "delivered": self.delivered,
                "met": self.delivered >= self.wanted}
