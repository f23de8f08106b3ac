"""The plant's figures, contributed by its sources and sinks: the tally (bottles in, delivered, misrouted, on the line, throughput), jams and orders."""
