"""The reference semantics in Python: steps a Net exactly as the FMU compiled from it does."""

import math

INT32_MAX = 2**31 - 1
_FIXED_TIME_LIMIT_NS = 2**62  # framework/fixed_time.h


def ns_from_seconds(seconds):
    """Seconds rounded to the nearest nanosecond, halves away from zero: C's llround(seconds * 1e9)."""
    scaled = seconds * 1e9  # the same double product as the C code
    if not abs(scaled) < _FIXED_TIME_LIMIT_NS:
        raise ValueError(f"{seconds} s is beyond the {_FIXED_TIME_LIMIT_NS / 1e9:g} s a delay can count")
    magnitude = abs(scaled)
    whole = math.floor(magnitude)
    rounded = int(whole) + (1 if magnitude - whole >= 0.5 else 0)  # exact: both terms are doubles near each other
    return rounded if scaled >= 0 else -rounded


class Interpreter:
    """One instance of a net: its marking, what arrived in the last step, and the waits of delayed transitions.

    start_values take the FMU's parameter names: <place>_initial, <transition>_delay."""

    def __init__(self, net, start_values=None):
        self.net = net
        values = dict(start_values or {})
        known = {f"{p.name}_initial" for p in net.places} | {f"{t.name}_delay" for t in net.delayed}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(f"net '{net.name}' has no parameter {', '.join(unknown)}")
        self.tokens = {}
        for place in net.places:
            marking = values.get(f"{place.name}_initial", place.marking)
            if not isinstance(marking, int) or not 0 <= marking <= INT32_MAX:
                raise ValueError(f"{place.name}_initial must be an integer from 0 to {INT32_MAX}, got {marking!r}")
            self.tokens[place.name] = marking
        self.got = dict.fromkeys(self.tokens, False)
        self.fired = ()
        self._delay_ns = {}
        for transition in net.delayed:
            delay = values.get(f"{transition.name}_delay", transition.delay)
            if not delay >= 0:  # the FMU's parameter has min 0; this also refuses NaN
                raise ValueError(f"{transition.name}_delay must not be negative, got {delay!r}")
            self._delay_ns[transition.name] = ns_from_seconds(delay)
        self._since_ns = {}  # delayed transition -> start of the step since which it has been enabled

    def step(self, t, h, put=()):
        """One update step from t to t + h; put names the places whose <place>_put is true in it."""
        put = set(put)
        unknown = sorted(put - set(self.tokens))
        if unknown:
            raise ValueError(f"net '{self.net.name}' has no place {', '.join(unknown)}")
        if h < 0:
            raise ValueError(f"step size {h} is negative")
        now_ns = end_ns = 0
        if self._delay_ns:  # like the C code, which converts time only when a delay needs it
            now_ns, end_ns = ns_from_seconds(t), ns_from_seconds(t + h)

        # 1. Puts.
        marking = {place: tokens + (place in put) for place, tokens in self.tokens.items()}
        # 2. Every transition enabled in that marking fires; they are all decided before any token moves.
        fired = [transition for transition in self.net.transitions
                 if self._fires(transition, marking, now_ns, end_ns)]
        # 3. Take (never more than a place holds), then give.
        taken = dict.fromkeys(marking, 0)
        given = dict.fromkeys(marking, 0)
        for transition in fired:
            for place, weight in transition.takes:
                taken[place] += weight
            for place, weight in transition.gives:
                given[place] += weight
        after = {place: max(0, marking[place] - taken[place]) + given[place] for place in marking}
        for place, tokens in after.items():
            if tokens > INT32_MAX:
                raise OverflowError(f"place {place} would hold {tokens} tokens, more than an FMI Integer holds")
        self.tokens = after
        self.got = {place: place in put or given[place] > 0 for place in marking}
        self.fired = tuple(transition.name for transition in fired)

    def _fires(self, transition, marking, now_ns, end_ns):
        enabled = (all(marking[place] >= weight for place, weight in transition.inputs)
                   and all(marking[place] < weight for place, weight in transition.inhibitors))
        if transition.delay is None:
            return enabled
        if not enabled:
            self._since_ns.pop(transition.name, None)
            return False
        since = self._since_ns.setdefault(transition.name, now_ns)
        if end_ns - since < self._delay_ns[transition.name]:
            return False
        del self._since_ns[transition.name]  # it fires: the next enabling starts a new wait
        return True

    def outputs(self):
        """The FMU's outputs by variable name: <place>_tokens, <place>_marked, <place>_got."""
        values = {}
        for place, tokens in self.tokens.items():
            values[f"{place}_tokens"] = tokens
            values[f"{place}_marked"] = tokens > 0
            values[f"{place}_got"] = self.got[place]
        return values
