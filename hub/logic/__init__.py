"""Logic transports: every FMI call (the FMI adapter), isolated FMUs, in-process participants, FMUs served on the bus, remote slaves, and the factory that picks one."""
