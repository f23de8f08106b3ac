"""Plant element types. CATALOGUE maps each module name to its class, imported on first use."""

CATALOGUE = {
    "bottle": "modules.bottle:Bottle",
    "clock": "modules.clock:ClockModule",
    "connector": "modules.connector:Connector",
    "constant": "modules.constant:Constant",
    "conveyor": "modules.conveyor:Conveyor",
    "curve": "modules.curve:Curve",
    "fmu": "modules.fmu:Fmu",
    "inspector": "modules.inspector:Inspector",
    "id_reader": "modules.id_reader:IdReader",
    "light_barrier": "modules.light_barrier:LightBarrier",
    "participant": "modules.participant:ParticipantModule",
    "pusher": "modules.pusher:Pusher",
    "robot_arm": "modules.robot_arm:RobotArm",
    "separator": "modules.separator:Separator",
    "sink": "modules.sink:Sink",
    "source": "modules.source:Source",
    "ssp": "modules.ssp:Ssp",
    "station": "modules.station:Station",
    "stopper": "modules.stopper:Stopper",
    "switch": "modules.switch:Switch",
}
