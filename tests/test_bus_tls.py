"""The bus over TLS, on loopback, with certificates made for the test: a run gives the same recording
as over tcp; a participant without the right authority or certificate cannot join, and says why.

    drive.logic ══ tls/127.0.0.1 (mutual) ══ python -m modules.belt_drive_logic
"""
import json
import shutil
import time

import pytest
import trustme

from hub.bus.session import Bus, BusError, free_loopback_endpoint, wait_until
from hub.bus.settings import BusSettings
from hub.bus.tls import TlsSettings
from hub.core.errors import ScenarioError, SimulationError
from hub.scenario.checker import load_scenario

from .bus_support import BELT_FMU, BELT_PARTICIPANT, hub, output_of, process, same_files
from .dataplane_support import every_point, settle
from .helpers import ROOT, run_scenario


@pytest.fixture(scope="module")
def certs(tmp_path_factory):
    """An authority with the hub's certificate (for 127.0.0.1), a participant's and an HMI's, each
    with its name as common name; a second, unrelated authority with a certificate of its own."""
    folder = tmp_path_factory.mktemp("certs")
    ca, stranger = trustme.CA(), trustme.CA()
    ca.cert_pem.write_to_path(folder / "ca.pem")
    stranger.cert_pem.write_to_path(folder / "stranger_ca.pem")
    for name, authority, identities in (("hub", ca, ("127.0.0.1", "localhost")), ("plc", ca, ("plc.example",)),
                                        ("hmi", ca, ("hmi.example",)), ("intruder", stranger, ("intruder.example",))):
        cert = authority.issue_cert(*identities, common_name=name)
        cert.private_key_pem.write_to_path(folder / f"{name}.key")
        cert.cert_chain_pems[0].write_to_path(folder / f"{name}.pem")
    return folder


def tls_section(certs, **extra):
    return {"ca": str(certs / "ca.pem"), "certificate": str(certs / "hub.pem"), "key": str(certs / "hub.key"),
            "mutual": True, **extra}


def tls_endpoint() -> str:
    return free_loopback_endpoint().replace("tcp/", "tls/")


@pytest.fixture(scope="module")
def over_tcp(tmp_path_factory):
    out = tmp_path_factory.mktemp("over_tcp")
    run_scenario(BELT_PARTICIPANT, out)
    return out


def test_a_launched_participant_joins_over_mutual_tls_and_the_recording_is_the_same(certs, over_tcp, tmp_path):
    """The hub listens on tls/ only and asks for client certificates; the process it launches is
    given the authority and the hub's certificate in its environment, and so has the hub's rights
    under access control."""
    endpoint = tls_endpoint()
    run_scenario(BELT_PARTICIPANT, tmp_path, {"run.bus": {"listen": [endpoint], "tls": tls_section(certs),
                                                          "access": {"control": []}}})
    assert same_files(over_tcp, tmp_path)


def test_a_joining_participant_with_its_own_certificate_gives_the_same_recording(certs, over_tcp, tmp_path):
    """Its certificate's common name, plc, is one access control lets act on the control plane."""
    scene = tmp_path / "joined.yaml"
    scene.write_text(BELT_PARTICIPANT.read_text().replace("    command: [python, -m, modules.belt_drive_logic]\n", ""))
    settings = BusSettings(listen=(tls_endpoint(),), tls=load_scenario(
        scene, {"run.bus": {"tls": tls_section(certs)}}).run.bus.tls, control=("plc",))
    with Bus(settings) as bus, hub(scene, tmp_path / "out", {"name": "belt_ramp_participant"}, bus=bus) as master:
        with process("-m", "modules.belt_drive_logic", "--run", "belt_ramp_participant", "--name", "drive",
                     "--connect", bus.endpoints[0], "--tls-ca", certs / "ca.pem",
                     "--tls-cert", certs / "plc.pem", "--tls-key", certs / "plc.key") as proc:
            master.run()
            assert output_of(proc)[0] == 0
    assert same_files(over_tcp, tmp_path / "out")


@pytest.mark.parametrize("options, why", [
    (["--tls-ca", "stranger_ca.pem", "--tls-cert", "plc.pem", "--tls-key", "plc.key"],
     "its certificate is not signed by the authority in {certs}/stranger_ca.pem "
     "(unable to get local issuer certificate)"),
    (["--tls-ca", "ca.pem", "--tls-cert", "intruder.pem", "--tls-key", "intruder.key"],
     "it does not accept our certificate {certs}/intruder.pem: not signed by an authority it trusts "
     "(tlsv1_alert_unknown_ca)"),
], ids=["wrong authority", "certificate of another authority"])
def test_a_launched_participant_with_the_wrong_certificates_stops_the_run_with_the_reason(certs, tmp_path,
                                                                                         options, why):
    """Options on the participant's command line win over what the hub puts in its environment."""
    endpoint = tls_endpoint()
    command = ["python", "-m", "modules.belt_drive_logic"] + [
        str(certs / o) if o.endswith((".pem", ".key")) else o for o in options]
    with pytest.raises(SimulationError) as info:
        run_scenario(BELT_PARTICIPANT, tmp_path, {"run.bus": {"listen": [endpoint], "tls": tls_section(certs)},
                                                  "objects.drive.command": command})
    message = str(info.value)
    assert message.startswith("participant 'drive': its process exited with code 1 before it could join")
    assert (f"planthub participant 'drive': cannot join over TLS; {endpoint} refused the handshake: "
            f"{why.format(certs=certs)}") in message


def test_a_joining_participant_without_a_certificate_is_told_the_hub_wants_one(certs):
    with Bus(BusSettings(listen=(tls_endpoint(),), tls=TlsSettings(
            str(certs / "ca.pem"), str(certs / "hub.pem"), str(certs / "hub.key"), mutual=True))) as bus:
        with process("-m", "modules.belt_drive_logic", "--run", "r", "--name", "drive",
                     "--connect", bus.endpoints[0], "--tls-ca", certs / "ca.pem") as proc:
            code, _, err = output_of(proc)
    assert code == 1
    assert err.strip() == (f"planthub participant 'drive': cannot join over TLS; {bus.endpoints[0]} refused the "
                           f"handshake: it asks for a client certificate (mutual TLS) and none was given")


def test_a_joining_participant_without_the_authority_is_told_to_give_it(certs):
    with process("-m", "modules.belt_drive_logic", "--run", "r", "--name", "drive",
                 "--connect", "tls/127.0.0.1:7447") as proc:
        code, _, err = output_of(proc)
    assert code == 2
    assert err.strip().endswith("error: --connect: tls/127.0.0.1:7447 is a TLS endpoint: give --tls-ca, "
                                "the authority that signed the hub's certificate")


def test_an_operator_command_goes_over_tls(certs, tmp_path):
    """`planthub send` and the Viewer take the same certificates as a participant."""
    from hub.live import Viewer

    settings = BusSettings(listen=(tls_endpoint(),), tls=TlsSettings(
        str(certs / "ca.pem"), str(certs / "hub.pem"), str(certs / "hub.key"), mutual=True))
    plc = TlsSettings(str(certs / "ca.pem"), str(certs / "plc.pem"), str(certs / "plc.key"), mutual=True)
    with Bus(settings) as bus, hub(BELT_FMU, tmp_path, bus=bus) as master, \
            Viewer("belt_ramp_fmu", bus.endpoints, tls=plc) as operator:
        master.start()
        ident = operator.command("stop", by="test", wait=None)
        master.run()
        assert operator.answer(ident, 5.0)["ok"]
    assert master.stopped_by.startswith("stopped by an operator")


def hub_settings(certs, control=None, watch=(), instructor=()) -> BusSettings:
    return BusSettings(listen=(tls_endpoint(),), control=control, watch=watch, instructor=instructor, tls=TlsSettings(
        str(certs / "ca.pem"), str(certs / "hub.pem"), str(certs / "hub.key"), mutual=True))


def own(certs, name) -> TlsSettings:
    return TlsSettings(str(certs / "ca.pem"), str(certs / f"{name}.pem"), str(certs / f"{name}.key"), mutual=True)


def test_under_access_control_a_watch_role_may_watch_and_ask_rates_but_not_command(certs, tmp_path):
    """Zenoh drops what access control denies without a word: the command gets no answer and the
    run goes to its end, while the samples the HMI watches keep coming, at the rate it asked."""
    from hub.core.errors import PlanthubError
    from hub.live import Viewer

    with Bus(hub_settings(certs, control=("plc",), watch=("hmi",))) as bus, \
            every_point(BELT_FMU, tmp_path, bus=bus) as master, \
            Viewer("belt_ramp_fmu", bus.endpoints, tls=own(certs, "hmi")) as hmi:
        master.start()
        hmi.watch("drive/logic/speed", period=0.1)   # a rate request: it sees the hub's token, the hub its put
        settle(master, lambda: master.dataplane.live and hmi.id in master.dataplane.requests)
        ident = hmi.command("stop", by="hmi", wait=None)
        master.run()
        ticks = [s.tick for s in iter(lambda: hmi.next(timeout=1.0), None)]
        with pytest.raises(PlanthubError, match="no answer to command"):
            hmi.answer(ident, 0.5)
    assert ticks == list(range(0, 901, 15))   # every 0.1 s: the rate it asked for, to the last point
    assert not master.stopped_by
    assert not (tmp_path / "commands.csv").exists()


def test_under_access_control_only_an_instructor_reaches_the_instructors_key(certs, tmp_path):
    """A controller's fault on the instructor's key is dropped by Zenoh (no answer, nothing recorded);
    an instructor's — a name in access.instructor, not in control — is applied and answered."""
    from hub.core.errors import PlanthubError
    from hub.live import Viewer

    slow = {"name": "slow", "kind": "belt_failure", "speed": 0.5}
    with Bus(hub_settings(certs, control=("plc",), instructor=("hmi",))) as bus, \
            hub(BELT_FMU, tmp_path, bus=bus) as master, \
            Viewer("belt_ramp_fmu", bus.endpoints, tls=own(certs, "plc")) as plc, \
            Viewer("belt_ramp_fmu", bus.endpoints, tls=own(certs, "hmi")) as teacher:
        master.start()
        dropped = plc.command("fault", "belt.drive", {**slow, "name": "plc's"}, wait=None, instructor=True)
        applied = teacher.command("fault", "belt.drive", slow, by="teacher", wait=None, instructor=True)
        assert wait_until(master.commands.pending, 5.0)
        master.run()
        assert teacher.answer(applied, 5.0)["ok"] is True
        with pytest.raises(PlanthubError, match="no answer to command"):
            plc.answer(dropped, 0.5)
    assert [line.split(",")[2:4] for line in (tmp_path / "commands.csv").read_text().splitlines()[1:]] == [
        ["fault", "belt.drive"]]


def test_under_access_control_a_control_role_may_watch_too(certs, tmp_path):
    from hub.live import Viewer

    with Bus(hub_settings(certs, control=("plc",), watch=("hmi",))) as bus, hub(BELT_FMU, tmp_path, bus=bus) as master, \
            Viewer("belt_ramp_fmu", bus.endpoints, tls=own(certs, "plc")) as plc:
        master.start()
        plc.watch("drive/logic/speed")
        settle(master, lambda: master.dataplane.live)
        master.run()
        assert plc.next(timeout=5.0) is not None


def test_under_access_control_a_certificate_named_nowhere_watches_nothing(certs, tmp_path):
    """Signed by the authority, so it connects; named neither in watch nor in control, so its
    subscription and its rate request never reach the hub, and nothing reaches it. Denials are
    silent: the hub is asked what it learned, and the viewer gets a bounded wait after the run."""
    from hub.bus import wire
    from hub.core.errors import PlanthubError
    from hub.live import Viewer

    with Bus(hub_settings(certs, control=("plc",), watch=("operator",))) as bus, \
            hub(BELT_FMU, tmp_path, bus=bus) as master, \
            Viewer("belt_ramp_fmu", bus.endpoints, tls=own(certs, "hmi")) as hmi:
        master.start()
        hmi.watch("**")
        hmi.bus.put(wire.control_key("belt_ramp_fmu", "viewer", hmi.id, "rate"),
                    wire.pack({"key": "plant/belt_ramp_fmu/**", "period": 0.1}), wire.MSGPACK)
        time.sleep(1.0)   # what a listed viewer needs here is milliseconds (the tests above)
        master.dataplane.update()
        learned = (list(master.dataplane.live), dict(master.dataplane.requests), set(master.dataplane.viewers))
        master.run()
        got = hmi.next(timeout=1.0)
        with pytest.raises(PlanthubError, match="no hub for run 'belt_ramp_fmu' within 0.5 s"):
            hmi.wait_for_hub(0.5)   # not even the hub's liveliness token
    assert learned == ([], {}, set())
    assert got is None
    assert hmi.state == {}   # nor the run's state


def test_under_access_control_a_participant_not_named_cannot_join(certs, tmp_path):
    scene = tmp_path / "joined.yaml"
    scene.write_text(BELT_PARTICIPANT.read_text().replace("    command: [python, -m, modules.belt_drive_logic]\n",
                                                          "    join_timeout: 2\n"))
    with Bus(hub_settings(certs, control=("plc",), watch=("hmi",))) as bus, hub(scene, bus=bus) as master:
        with process("-m", "modules.belt_drive_logic", "--run", "joined", "--name", "drive",
                     "--connect", bus.endpoints[0], "--tls-ca", certs / "ca.pem",
                     "--tls-cert", certs / "hmi.pem", "--tls-key", certs / "hmi.key") as proc:
            with pytest.raises(SimulationError, match="participant 'drive' did not join within 2 s"):
                master.run()
            code, _, err = output_of(proc)
    # A watch role: it saw the hub and the run's state, but its hello went nowhere.
    assert (code, err) == (1, "planthub participant 'drive': the run stopped before I could join\n")


def test_a_launched_participant_with_its_own_certificate_joins_under_access_control_without_the_hubs_key(
        certs, over_tcp, tmp_path):
    """`tls: {certificate, key}` on the object, relative to the scenario file: the process is handed
    that certificate, not the hub's (it writes what its environment holds), joins as `plc`, the one
    name access control lets serve logic, and the hub does not warn."""
    shutil.copytree(certs, tmp_path / "certs")
    told = tmp_path / "told.json"
    scene = tmp_path / "belt_ramp_participant.yaml"
    scene.write_text(BELT_PARTICIPANT.read_text().replace(
        "    command: [python, -m, modules.belt_drive_logic]\n",
        f"    command: [python, -m, tests.participants.tells_its_tls, '{told}']\n    cwd: '{ROOT}'\n"
        "    tls: {certificate: certs/plc.pem, key: certs/plc.key}\n"))
    notes = []
    run_scenario(scene, tmp_path / "out", {"run.bus": {"listen": [tls_endpoint()], "tls": tls_section(certs),
                                                       "access": {"control": ["plc"]}}}, log=notes.append)
    assert same_files(over_tcp, tmp_path / "out")
    env = json.loads(told.read_text())
    assert (env["PLANTHUB_TLS_CERT"], env["PLANTHUB_TLS_KEY"]) == (str(tmp_path / "certs" / "plc.pem"),
                                                                   str(tmp_path / "certs" / "plc.key"))
    assert env["PLANTHUB_TLS_CA"] == str(certs / "ca.pem")
    assert not [value for value in env.values() if "hub." in value]
    assert not [note for note in notes if "own certificate and private key" in note]


def test_a_launched_participant_without_a_certificate_of_its_own_gets_the_hubs_with_a_warning(certs, tmp_path):
    told = tmp_path / "told.json"
    notes = []
    run_scenario(BELT_PARTICIPANT, tmp_path / "out", {
        "run.bus": {"listen": [tls_endpoint()], "tls": tls_section(certs), "access": {"control": []}},
        "objects.drive.command": ["python", "-m", "tests.participants.tells_its_tls", str(told)],
        "objects.drive.cwd": str(ROOT)}, log=notes.append)
    env = json.loads(told.read_text())
    assert (env["PLANTHUB_TLS_CERT"], env["PLANTHUB_TLS_KEY"]) == (str(certs / "hub.pem"), str(certs / "hub.key"))
    assert ("participant 'drive' is launched with the hub's own certificate and private key (PLANTHUB_TLS_KEY): "
            "it can act as the hub on the bus; give it a certificate of its own with `tls: {certificate, key}` "
            "on its object") in notes


def test_an_fmu_served_by_a_launched_process_presents_its_own_certificate(certs, tmp_path):
    """`planthub serve-fmu`, launched for `runs: bus`, joins as `plc` under access control."""
    notes = []
    run_scenario(BELT_FMU, tmp_path / "out", {
        "run.bus": {"listen": [tls_endpoint()], "tls": tls_section(certs), "access": {"control": ["plc"]}},
        "objects.drive.runs": "bus",
        "objects.drive.tls": {"certificate": str(certs / "plc.pem"), "key": str(certs / "plc.key")}},
        log=notes.append)
    over_the_hub = tmp_path / "in_hub"
    run_scenario(BELT_FMU, over_the_hub)
    assert same_files(over_the_hub, tmp_path / "out")
    assert not [note for note in notes if "own certificate and private key" in note]


# --- bad set-ups: named, with file and line ------------------------------------------------------
def scenario_problems(write_scenario, bus: str) -> list[str]:
    path = write_scenario(f"""
        planthub: 1
        run:
          bus: {bus}
        objects:
          c: {{module: constant, type: real, value: 1}}
        """)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return [str(p).replace(str(path), "scene.yaml").replace(str(path.parent), "DIR") for p in info.value.problems]


def test_a_tls_endpoint_without_certificates_is_named(write_scenario):
    assert scenario_problems(write_scenario, "{listen: [tls/0.0.0.0:7447], connect: [tls/10.0.0.2:7447]}") == [
        "scene.yaml:3: run.bus.listen[0]: tls/0.0.0.0:7447 is a TLS endpoint: give the TLS settings with "
        "a certificate and its key",
        "scene.yaml:3: run.bus.connect[0]: tls/10.0.0.2:7447 is a TLS endpoint: give the TLS settings with "
        "the authority (ca) that signed the certificate of the other side"]


def test_missing_certificate_files_are_named_relative_to_the_scenario(write_scenario):
    problems = scenario_problems(write_scenario, """
            listen: [tls/0.0.0.0:7447]
            tls: {ca: certs/ca.pem, certificate: certs/hub.pem, key: certs/hub.key}""")
    assert problems == [
        "scene.yaml:5: run.bus.tls.ca: no such file: DIR/certs/ca.pem",
        "scene.yaml:5: run.bus.tls.certificate: no such file: DIR/certs/hub.pem",
        "scene.yaml:5: run.bus.tls.key: no such file: DIR/certs/hub.key"]


def test_incomplete_tls_settings_are_named(write_scenario, certs):
    problems = scenario_problems(write_scenario, f"""
            listen: [tls/0.0.0.0:7447]
            tls:
              mutual: true
              key: {certs}/hub.key""")
    assert problems == [
        "scene.yaml:5: run.bus.tls.ca: missing: the certificate of the authority that signed the certificates "
        "(the hub's, and with mutual TLS the participants')",
        "scene.yaml:5: run.bus.tls.certificate: missing: the key needs its certificate",
        "scene.yaml:4: run.bus.listen[0]: listening on tls/0.0.0.0:7447 needs a certificate and its key"]


def test_files_that_are_not_what_they_should_be_are_named(write_scenario, certs, tmp_path):
    (tmp_path / "notes.txt").write_text("not a certificate\n")
    problems = scenario_problems(write_scenario, f"""
            listen: [tls/0.0.0.0:7447]
            tls: {{ca: notes.txt, certificate: {certs}/hub.pem, key: {certs}/plc.key}}""")
    assert problems == [
        "scene.yaml:5: run.bus.tls.ca: DIR/notes.txt holds no PEM certificate (no '-----BEGIN CERTIFICATE-----' line)",
        f"scene.yaml:5: run.bus.tls.key: {certs}/plc.key is not the key of the certificate {certs}/hub.pem"]


def test_tls_settings_with_no_tls_endpoint_are_named(write_scenario, certs):
    problems = scenario_problems(write_scenario, f"""
            listen: [tcp/0.0.0.0:7447]
            tls: {{ca: {certs}/ca.pem, certificate: {certs}/hub.pem, key: {certs}/hub.key}}""")
    assert problems == ["scene.yaml:5: run.bus.tls: no endpoint uses it (tcp/0.0.0.0:7447): write tls/HOST:PORT"]


def test_the_access_section_names_who_may_watch(write_scenario, certs):
    path = write_scenario(f"""
        planthub: 1
        run:
          bus:
            listen: [tls/127.0.0.1:7447]
            tls: {{ca: {certs}/ca.pem, certificate: {certs}/hub.pem, key: {certs}/hub.key, mutual: true}}
            access: {{control: [plc], watch: [hmi, dashboard]}}
        objects:
          c: {{module: constant, type: real, value: 1}}
        """)
    bus = load_scenario(path).run.bus
    assert (bus.control, bus.watch) == (("plc",), ("hmi", "dashboard"))
    assert BusSettings().watch == ()


def test_access_control_without_mutual_tls_is_named(write_scenario, certs):
    problems = scenario_problems(write_scenario, f"""
            listen: [tls/0.0.0.0:7447]
            tls: {{ca: {certs}/ca.pem, certificate: {certs}/hub.pem, key: {certs}/hub.key}}
            access: {{control: [plc]}}""")
    assert problems == ["scene.yaml:6: run.bus.access: access control tells participants apart by their "
                        "certificates: it needs run.bus.tls with mutual: true"]


def test_a_tls_listen_flag_without_tls_settings_cannot_open_the_bus():
    """`planthub run --listen tls/…` on a scenario without run.bus.tls: the bus says what is missing."""
    with pytest.raises(BusError) as info:
        Bus(BusSettings(listen=("tls/127.0.0.1:7447",)))
    assert str(info.value) == ("cannot open the bus: run.bus.listen[0]: tls/127.0.0.1:7447 is a TLS endpoint: "
                               "give the TLS settings with a certificate and its key")


# --- a launched participant's own certificate, checked at load -------------------------------------
OWN_CERTIFICATE = """
    planthub: 1
    run:
      bus:
        listen: [tls/127.0.0.1:7447]
        tls: {{ca: {certs}/ca.pem, certificate: {certs}/hub.pem, key: {certs}/hub.key, mutual: true}}
        access: {{control: [plc]}}
    objects:
      drive:
        module: participant
        outputs: {{speed: real}}
        command: [python, -m, modules.belt_drive_logic]
        tls: {tls}
    """


def own_certificate_problems(write_scenario, certs, tls: str, text: str = OWN_CERTIFICATE) -> list[str]:
    path = write_scenario(text.format(certs=certs, tls=tls))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    return [str(p).replace(str(path), "scene.yaml").replace(str(certs), "CERTS").replace(str(path.parent), "DIR")
            for p in info.value.problems]


def test_a_participants_own_certificate_files_are_named_relative_to_the_scenario(write_scenario, certs):
    assert own_certificate_problems(write_scenario, certs, "{certificate: certs/plc.pem, key: certs/plc.key}") == [
        "scene.yaml:12: objects.drive.tls.certificate: no such file: DIR/certs/plc.pem",
        "scene.yaml:12: objects.drive.tls.key: no such file: DIR/certs/plc.key"]


def test_a_participants_key_that_is_not_its_certificates_is_named(write_scenario, certs):
    assert own_certificate_problems(write_scenario, certs, f"{{certificate: {certs}/plc.pem, key: {certs}/hmi.key}}") == [
        "scene.yaml:12: objects.drive.tls.key: CERTS/hmi.key is not the key of the certificate CERTS/plc.pem"]


def test_a_participants_certificate_whose_name_access_control_does_not_list_is_named(write_scenario, certs):
    assert own_certificate_problems(write_scenario, certs, f"{{certificate: {certs}/hmi.pem, key: {certs}/hmi.key}}") == [
        "scene.yaml:12: objects.drive.tls.certificate: CERTS/hmi.pem names 'hmi' (its common name), which "
        "run.bus.access.control does not list (plc): the participant could not serve its logic; add 'hmi' to control"]


def test_a_participants_certificate_of_another_authority_is_named(write_scenario, certs):
    assert own_certificate_problems(write_scenario, certs,
                                    f"{{certificate: {certs}/intruder.pem, key: {certs}/intruder.key}}") == [
        "scene.yaml:12: objects.drive.tls.certificate: CERTS/intruder.pem is not signed by the run's authority "
        "CERTS/ca.pem (run.bus.tls.ca): the hub would refuse its handshake",
        "scene.yaml:12: objects.drive.tls.certificate: CERTS/intruder.pem names 'intruder' (its common name), which "
        "run.bus.access.control does not list (plc): the participant could not serve its logic; add 'intruder' to "
        "control"]


def test_a_participants_certificate_without_its_key_is_named(write_scenario, certs):
    assert own_certificate_problems(write_scenario, certs, f"{{certificate: {certs}/plc.pem}}") == [
        "scene.yaml:12: objects.drive.tls: 'key' is missing"]


def test_a_participants_certificate_on_a_bus_without_tls_is_named(write_scenario, certs):
    text = OWN_CERTIFICATE.replace("listen: [tls/127.0.0.1:7447]", "listen: [tcp/127.0.0.1:7447]").replace(
        "        tls: {{ca: {certs}/ca.pem, certificate: {certs}/hub.pem, key: {certs}/hub.key, mutual: true}}\n", "")
    text = text.replace("        access: {{control: [plc]}}\n", "")
    assert own_certificate_problems(write_scenario, certs, f"{{certificate: {certs}/plc.pem, key: {certs}/plc.key}}",
                                    text) == [
        "scene.yaml:10: objects.drive.tls: the run's bus does not use TLS (no run.bus.tls), so a certificate of the "
        "participant's own has no use: give run.bus.tls, or leave this out"]


def test_a_certificate_for_a_process_the_hub_does_not_launch_is_named(write_scenario, certs):
    own = f"{{certificate: {certs}/plc.pem, key: {certs}/plc.key}}"
    joins = OWN_CERTIFICATE.replace("        command: [python, -m, modules.belt_drive_logic]\n", "")
    assert own_certificate_problems(write_scenario, certs, own, joins) == [
        "scene.yaml:11: objects.drive.tls: the hub launches no process here (no `command` or `python`): a "
        "participant that joins by itself presents its own certificate (--tls-cert, --tls-key)"]
    fmu = OWN_CERTIFICATE.replace("""        module: participant
        outputs: {{speed: real}}
        command: [python, -m, modules.belt_drive_logic]""", f"""        module: fmu
        file: {ROOT}/build/fmus/belt_drive-fmi2.fmu
        runs: bus
        launch: false""")
    assert own_certificate_problems(write_scenario, certs, own, fmu) == [
        "scene.yaml:13: objects.drive.tls: a certificate goes with runs: bus, a process the hub starts on the bus; "
        "one that joins (launch: false) presents its own (serve-fmu --tls-cert, --tls-key)"]


def test_the_scene_says_who_may_command_and_a_watch_only_view_is_told_why(certs):
    """A view greys its panel out for a certificate access control lets only watch; it learns the
    rules from the scene document (hub/view/scene.py) and its own certificate's common name."""
    from hub.bus.tls import common_name
    from hub.run.plant import Plant
    from hub.view.scene import refusal, scene_document

    scenario = load_scenario(BELT_FMU, {"run.bus": {"listen": [tls_endpoint()], "tls": tls_section(certs),
                                                    "access": {"control": ["plc"], "watch": ["hmi"]}}})
    with Plant(scenario) as plant:
        scene = scene_document(plant, "belt_ramp_fmu")
    assert scene["access"] == {"control": ["plc", "hub"], "watch": ["hmi"], "instructor": ["hub"]}, \
        "the hub's own name controls (and instructs) too"
    assert refusal(scene, common_name(str(certs / "plc.pem"))) is None
    assert refusal(scene, common_name(str(certs / "hmi.pem"))) == (
        "this view's certificate names 'hmi', which may only watch this run (run.bus.access.control: plc, hub)")
    assert refusal(scene, None) == ("the run's bus is under access control (run.bus.access) and this view shows "
                                    "no certificate: it may watch at most")
    with Plant(load_scenario(BELT_FMU)) as plant:
        open_scene = scene_document(plant, "belt_ramp_fmu")
    assert open_scene["access"] is None and refusal(open_scene, None) is None
