"""A run that ends with its orders: `run.orders` bottles out of the plant, taken by any of its sinks
(a reject lane's included: an order is out once its bottle left the line, delivered or rejected)."""
from __future__ import annotations

from dataclasses import dataclass

from hub.core.observer import Stop
from hub.scenario.expectations import Implied, Outcome
from modules.sink import Bin


class Orders:
    """Counts the bottles the sinks took (delivered, rightly or not, or rejected) against the number
    wanted: a stop condition (hub/core/observer.py) that sinks contribute (Module.CONTRIBUTES)."""

    def __init__(self, plant, wanted: int):
        self.wanted = wanted
        self.rate = plant.scenario.run.physics_rate
        self.bins = [c for c in plant.components if isinstance(c, Bin)]

    @classmethod
    def for_plant(cls, plant) -> Orders | None:
        wanted = plant.scenario.run.orders
        return None if wanted is None else cls(plant, wanted)

    @property
    def out(self) -> int:
        """Bottles taken by any sink."""
        return sum(len(b.deliveries) for b in self.bins)

    @property
    def rejected(self) -> int:
        """Of those, the bottles the reject sinks took."""
        return sum(len(b.deliveries) for b in self.bins if b.rejects)

    def split(self) -> str:
        """How the orders out divide, when some were rejected: "(142 delivered, 8 rejected)"."""
        rejected = self.rejected
        return f" ({self.out - rejected} delivered, {rejected} rejected)" if rejected else ""

    def done(self) -> bool:
        return self.out >= self.wanted

    def stop(self, tick: int) -> Stop | None:
        if not self.done():
            return None
        return Stop(f"{self.wanted} orders out{self.split()} at t = {tick / self.rate:.9g} s (run.orders)",
                    ended=True)

    # --- what `run.orders` promises: judged by `planthub test`, said in the summary -------------
    def outcome(self, tick: int) -> Outcome:
        """The implied expectation: the run ended with its orders out."""
        met = Implied(f"the run ends with its {self.wanted} orders out (run.orders)")
        if self.done():
            return Outcome(met, True, f"{self.out} out{self.split()}")
        return Outcome(met, False, f"the run ended at t = {tick / self.rate:.9g} s with {self.out} of "
                                   f"{self.wanted} orders out")

    def section(self) -> OrdersLine:
        return OrdersLine(self.wanted, self.out, self.rejected)


@dataclass(frozen=True)
class OrdersLine:
    """The summary's line for `run.orders` (a SummarySection, hub/core/observer.py)."""

    wanted: int
    out: int           # bottles taken by any sink
    rejected: int      # of those, by a reject sink
    key = "orders"

    def lines(self) -> list[str]:
        if self.out >= self.wanted:
            return [f"  orders       {self.wanted} out (run.orders)"]
        return [f"  orders       {self.out} of {self.wanted} out: the run ended before its orders (run.orders)"]

    def as_dict(self) -> dict:
        return {"wanted": self.wanted, "out": self.out, "rejected": self.rejected, "met": self.out >= self.wanted}
