"""JSON Schema pieces shared by module parameter tables."""

POSITION = {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3}
YAW = {"type": "number", "default": 0.0, "description": "rotation about the vertical axis, degrees"}


def length(default=None, description=""):
    """A strictly positive length in metres."""
    schema = {"type": "number", "exclusiveMinimum": 0, "description": description}
    if default is not None:
        schema["default"] = default
    return schema


# A bottle's transport (hub/physics/transport.py): whether it may leave the engine while it rides
# a belt on which nothing can touch it, and how many ticks its tests look forward.
TRANSPORT = {
    "transport": {"enum": ["free", "engine"], "default": "free",
                  "description": "free: riding a belt with nothing within reach it leaves the engine and follows "
                                 "the belt's law in the hub (free transport; a hull or two-body bottle stays in the "
                                 "engine); engine: the engine moves it throughout"},
    "lookahead": {"type": "integer", "minimum": 2, "default": 6,
                  "description": "free transport: ticks its tests look forward; they are taken every lookahead − 1 ticks"},
}
