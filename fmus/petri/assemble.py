"""Turn a schema-checked Document into a Net, checking what spans entries: names, references, dead arcs."""

import math

from .net import Net, Place, Transition
from .problems import did_you_mean

ARC_KINDS = (("in", "input"), ("out", "output"), ("inhibit", "inhibitor"))


def assemble(name, document, problems, source):
    """The Net, or None if problems were found; tolerant of entries the schema already reported."""
    data = document.data if isinstance(document.data, dict) else {}
    places_data = data.get("places") if isinstance(data.get("places"), dict) else {}
    transitions_data = data.get("transitions") if isinstance(data.get("transitions"), dict) else {}
    line = document.line

    places = [Place(place, _marking(value), _description(value), line(("places", place)))
              for place, value in places_data.items()]
    _check_names(places_data, transitions_data, line, problems)

    transitions = []
    for transition, value in transitions_data.items():
        value = value if isinstance(value, dict) else {}
        path = ("transitions", transition)
        arcs = {}
        for key, kind in ARC_KINDS:
            found = _arcs(value.get(key))
            for place, _, where in found:
                if place not in places_data:
                    problems.add(line(path + (key, where)), f"transition '{transition}': {kind} arc to unknown "
                                 f"place '{place}'" + did_you_mean(place, places_data))
            arcs[key] = tuple((place, weight) for place, weight, _ in found)
        declared = any(value.get(key) not in (None, [], {}) for key, _ in ARC_KINDS)  # malformed ones included
        if not declared and path not in document.reported:
            problems.add(line(path), f"transition '{transition}' has no arcs: it would do nothing")
        inputs = dict(arcs["in"])
        for place, limit in arcs["inhibit"]:
            if place in inputs and limit <= inputs[place]:
                problems.add(line(path + ("inhibit",)),
                             f"transition '{transition}' can never fire: it needs {inputs[place]} token(s) on "
                             f"'{place}' but is inhibited from {limit}")
        delay = value.get("delay")
        if isinstance(delay, float) and math.isnan(delay):  # the schema's minimum cannot see NaN
            problems.add(line(path + ("delay",)), f"transition '{transition}': delay is NaN")
        transitions.append(Transition(transition, arcs["in"], arcs["out"], arcs["inhibit"],
                                      float(delay) if _is_number(delay) else None,
                                      _description(value), line(path)))
    if problems:
        return None
    return Net(name, str(data.get("description", "")), tuple(places), tuple(transitions), str(source))


def _check_names(places, transitions, line, problems):
    """Names must be unique across places and transitions, also ignoring case: VR_<NAME> is upper case."""
    seen = {}
    for kind, names in (("place", places), ("transition", transitions)):
        for name in names:
            key = str(name).upper()
            path = ("places" if kind == "place" else "transitions", name)
            if key in seen:
                other_kind, other, other_line = seen[key]
                same = "the same name" if other == name else "a name that differs only in case"
                problems.add(line(path), f"{kind} '{name}' has {same} as {other_kind} '{other}' (line {other_line}):"
                             " names must be unique across places and transitions, ignoring case")
            else:
                seen[key] = (kind, name, line(path))


def _arcs(value):
    """[(place, weight, key in value)] of the well-formed arcs in a list of names or a mapping name -> weight."""
    if isinstance(value, list):
        firsts = {}
        for index, place in enumerate(value):
            if isinstance(place, str):
                firsts.setdefault(place, index)  # a repeated name is the schema's to report
        return [(place, 1, index) for place, index in firsts.items()]
    if isinstance(value, dict):
        return [(place, int(w), place) for place, w in value.items() if _is_number(w) and w == int(w) and w >= 1]
    return []


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _marking(value):
    marking = value.get("marking", 0) if isinstance(value, dict) else value
    return int(marking) if _is_number(marking) and marking == int(marking) and marking >= 0 else 0


def _description(value):
    text = value.get("description", "") if isinstance(value, dict) else ""
    return text if isinstance(text, str) else ""
