"""The paper's test 2: bottles of 20 to 80 g put on belts at 1.0 m/s; the lighter ones rock more.

    bottle (at rest) ─► [==== belt, 1.0 m/s, F = gain·(v_tar − v) ====]   one belt per bottle
"""
import numpy as np

from hub.reports import paper

#: The largest inclination of a bottle gripped at its centre of mass (no torque at all): Bullet's
#: rigid contact rocks a sliding cylinder by up to this much, so smaller differences mean nothing.
CONTACT_FLOOR = 0.5


def by_model(run):
    out = {}
    for t in paper.tipping(run):
        out.setdefault(t.model, []).append(t)
    return {model: sorted(ts, key=lambda t: t.mass) for model, ts in out.items()}


def test_the_control_without_torque_stays_at_the_contact_floor(tipping_run):
    for t in by_model(tipping_run)["simple"]:
        assert t.first < CONTACT_FLOOR


def test_inclination_decreases_with_mass_for_both_base_models(tipping_run):
    for model in ("base_body", "base_point"):
        ts = by_model(tipping_run)[model]
        assert [round(t.mass * 1000) for t in ts] == [20, 35, 50, 65, 80]
        first = [t.first for t in ts]
        # Decreasing, up to the contact floor between heavier bottles that hardly rock at all …
        for lighter, heavier in zip(first, first[1:]):
            assert heavier <= lighter + CONTACT_FLOOR, (model, first)
        # … and clearly: the 20 g bottle rocks by degrees, several times the 80 g one.
        assert first[0] > 2.0 and first[0] > 3 * first[-1], (model, first)
        # It rocks back against the motion, then rights itself with a smaller second motion.
        light = ts[0]
        assert np.min(light.pitch) == -light.first
        assert light.second < light.first / 2


def test_no_bottle_tips_over(tipping_run):
    for t in paper.tipping(tipping_run):
        assert t.first < 10.0 and t.final < 1.0, t.bottle
