"""Every Zenoh call: the session, settings, wire format, TLS, lockstep, data plane, commands, viewers, launcher and the participant library.

Light on purpose: nothing here imports jsonschema, yaml, pybullet or fmpy, so a participant ships with this package alone."""
