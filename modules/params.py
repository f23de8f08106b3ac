"""JSON Schema pieces shared by module parameter tables."""

POSITION = {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3}
YAW = {"type": "number", "default": 0.0, "description": "rotation about the vertical axis, degrees"}


def length(default=None, description=""):
    """A strictly positive length in metres."""
    schema = {"type": "number", "exclusiveMinimum": 0, "description": description}
    if default is not None:
        schema["default"] = default
    return schema
