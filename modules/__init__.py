"""Plant element types. CATALOGUE maps each module name to its class, imported on first use."""

CATALOGUE = {
    "bottle": "modules.bottle:Bottle",
    "connector": "modules.connector:Connector",
    "constant": "modules.constant:Constant",
    "conveyor": "modules.conveyor:Conveyor",
    "fmu": "modules.fmu:Fmu",
    "light_barrier": "modules.light_barrier:LightBarrier",
}
