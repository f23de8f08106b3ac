"""The plant's figures, contributed by its sources and sinks: the tally (bottles in, delivered, misrouted, on the line, throughput), jams and orders."""

#: What a plant element contributes to a run (hub/core/module.py CONTRIBUTES).
FIGURES = "modules.plant.summary:PlantTally"
ORDERS = "modules.plant.orders:Orders.for_plant"
LOOK = "modules.plant.look:CargoLook"   # how bottles look in a view (hub/core/observer.py BodyLook)
