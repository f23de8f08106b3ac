"""Generate modelDescription.xml (FMI 2.0 and 3.0) and the C description of a model from its model.yaml."""

import argparse
import difflib
import hashlib
import json
import keyword
import math
import re
import sys
import uuid
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import yaml

GENERATION_TOOL = "planthub fmus/generate.py"

# Log categories of every FMU, in the order of the generated C enum; log.c maps
# a non-OK status onto the logStatus* category of the same name.
LOG_CATEGORIES = [
    ("logEvents", "Discrete events of the model: a timer fired, a setpoint was reached."),
    ("logStatusWarning", "Calls that returned a warning."),
    ("logStatusDiscard", "Calls that returned discard."),
    ("logStatusError", "Calls that returned an error, with the reason."),
    ("logStatusFatal", "Calls that returned fatal."),
]

TYPES = ("real", "int", "bool", "string")
STATE_TYPES = {"real": "double", "int32": "int32_t", "int64": "int64_t", "bool": "bool"}
C_TYPES = {"real": "double", "int": "int32_t", "bool": "bool", "string": "char *"}
C_TYPE_TAGS = {"real": "VAR_REAL", "int": "VAR_INT", "bool": "VAR_BOOL", "string": "VAR_STRING"}
C_START_MEMBER = {"real": "real", "int": "integer", "bool": "boolean", "string": "string"}
FMI2_ELEMENTS = {"real": "Real", "int": "Integer", "bool": "Boolean", "string": "String"}
FMI3_ELEMENTS = {"real": "Float64", "int": "Int32", "bool": "Boolean", "string": "String"}

# causality -> (allowed variabilities, default variability for real, default for the other types)
VARIABILITIES = {
    "parameter": (("fixed", "tunable"), "fixed", "fixed"),
    "input": (("discrete", "continuous"), "continuous", "discrete"),
    "output": (("discrete", "continuous"), "continuous", "discrete"),
    "local": (("discrete", "continuous"), "continuous", "discrete"),
}

TOP_KEYS = {"name", "description", "fmi_versions", "default_experiment", "variables", "state"}
VARIABLE_KEYS = {"name", "type", "causality", "variability", "start", "description", "unit", "min", "max"}
STATE_KEYS = {"name", "type", "description"}
EXPERIMENT_KEYS = {"start_time": "startTime", "stop_time": "stopTime", "step_size": "stepSize",
                   "tolerance": "tolerance"}

C_KEYWORDS = {
    "auto", "break", "case", "char", "const", "continue", "default", "do", "double", "else", "enum",
    "extern", "float", "for", "goto", "if", "inline", "int", "long", "register", "restrict", "return",
    "short", "signed", "sizeof", "static", "struct", "switch", "typedef", "union", "unsigned", "void",
    "volatile", "while", "_Bool", "_Complex", "_Imaginary", "bool", "true", "false",
}
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1


class DescriptionError(Exception):
    """Every problem found in model descriptions, one per line, each naming the file and line."""

    def __init__(self, problems):
        self.problems = list(problems)
        super().__init__("\n".join(self.problems))


def _located(path, problems):
    return DescriptionError(f"{path}:{line}: {text}" for line, text in problems)


class _Entry(dict):
    """A YAML mapping that remembers the line it starts on."""

    line = 0


class _Loader(yaml.SafeLoader):
    pass


def _construct_entry(loader, node):
    entry = _Entry(loader.construct_mapping(node, deep=True))
    entry.line = node.start_mark.line + 1
    return entry


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_entry)


@dataclass(frozen=True)
class Variable:
    name: str
    type: str
    causality: str
    variability: str
    start: object  # None means initial="calculated": the model computes it in its initialize hook
    description: str
    unit: str | None
    min: float | int | None
    max: float | int | None
    vr: int


@dataclass(frozen=True)
class StateField:
    name: str
    type: str
    description: str


@dataclass(frozen=True)
class Model:
    name: str
    description: str
    fmi_versions: tuple
    default_experiment: dict
    variables: tuple  # index == value reference; variables[0] is time
    state: tuple
    token: str
    source: str


# ---------------------------------------------------------------- reading


def load(model_dir):
    """Read and check model_dir/model.yaml; raise DescriptionError listing every problem."""
    path = Path(model_dir) / "model.yaml"
    text = path.read_text(encoding="utf-8")
    try:
        raw = yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        raise _located(path, [(mark.line + 1 if mark else 1, f"not valid YAML: {error}")]) from None
    problems = []
    model = _check_model(raw, Path(model_dir).name, problems)
    if problems:
        raise _located(path, problems)
    # The token changes exactly when the interface changes, so rebuilds are reproducible.
    canonical = json.dumps(raw, sort_keys=True, default=str)
    token = "{" + str(uuid.UUID(hashlib.sha256(canonical.encode()).hexdigest()[:32])) + "}"
    return Model(token=token, source=str(path), **model)


def _unknown_keys(entry, allowed, what, problems):
    for key in entry:
        if key not in allowed:
            hint = difflib.get_close_matches(str(key), sorted(allowed), n=1)
            suffix = f" (did you mean '{hint[0]}'?)" if hint else f" (allowed: {', '.join(sorted(allowed))})"
            problems.append((entry.line, f"{what}: unknown key '{key}'{suffix}"))


def _choice(value, allowed, what, line, problems):
    if value in allowed:
        return True
    hint = difflib.get_close_matches(str(value), list(allowed), n=1)
    suffix = f"did you mean '{hint[0]}'?" if hint else f"expected one of {', '.join(allowed)}"
    problems.append((line, f"{what} is '{value}': {suffix}"))
    return False


def _check_identifier(name, what, line, problems):
    if not isinstance(name, str) or not IDENTIFIER.match(name):
        problems.append((line, f"{what} '{name}' is not a C identifier ([A-Za-z_][A-Za-z0-9_]*)"))
        return False
    if name in C_KEYWORDS or keyword.iskeyword(name):
        problems.append((line, f"{what} '{name}' is a reserved word"))
        return False
    return True


def _check_model(raw, dir_name, problems):
    if not isinstance(raw, _Entry):
        problems.append((1, "the description must be a mapping with name, variables, ..."))
        return None
    _unknown_keys(raw, TOP_KEYS, "model", problems)
    name = raw.get("name")
    if _check_identifier(name, "model name", raw.line, problems) and name != dir_name:
        problems.append((raw.line, f"model name '{name}' must equal its directory name '{dir_name}'"))
    versions = raw.get("fmi_versions", [2, 3])
    if not isinstance(versions, list) or not versions or any(v not in (2, 3) for v in versions):
        problems.append((raw.line, f"fmi_versions is {versions!r}: expected a non-empty list of 2 and/or 3"))
        versions = []
    experiment = raw.get("default_experiment", {})
    if not isinstance(experiment, dict):
        problems.append((raw.line, "default_experiment must be a mapping"))
        experiment = {}
    elif isinstance(experiment, _Entry):
        _unknown_keys(experiment, set(EXPERIMENT_KEYS), "default_experiment", problems)
        for key, value in experiment.items():
            if key in EXPERIMENT_KEYS and not _is_finite_number(value):
                problems.append((experiment.line, f"default_experiment.{key} must be a finite number"))
    variables = _check_variables(raw.get("variables"), raw.line, problems)
    state = _check_state(raw.get("state", []), raw.line, {v.name for v in variables}, problems)
    return dict(name=name, description=str(raw.get("description", "")), fmi_versions=tuple(sorted(set(versions))),
                default_experiment=dict(experiment), variables=tuple(variables), state=tuple(state))


def _check_variables(entries, line, problems):
    time = Variable("time", "real", "independent", "continuous", None, "Simulation time", "s", None, None, 0)
    if not isinstance(entries, list) or not entries:
        problems.append((line, "variables must be a non-empty list"))
        return [time]
    variables, seen = [time], {"time": 0, "TIME": 0}
    for entry in entries:
        if not isinstance(entry, _Entry):
            problems.append((line, f"each variable must be a mapping, got {entry!r}"))
            continue
        variable = _check_variable(entry, len(variables), problems)
        if variable is None:
            continue
        for key in (variable.name, variable.name.upper()):  # VR_<NAME> must be unique too
            if key in seen:
                problems.append((entry.line, f"variable '{variable.name}' clashes with an earlier variable"
                                 + (" (time is predefined)" if key.lower() == "time" else "")))
                break
        else:
            seen.update({variable.name: 1, variable.name.upper(): 1})
            variables.append(variable)
    return variables


def _check_variable(entry, vr, problems):
    _unknown_keys(entry, VARIABLE_KEYS, f"variable '{entry.get('name')}'", problems)
    count = len(problems)
    name = entry.get("name")
    _check_identifier(name, "variable name", entry.line, problems)
    what = f"variable '{name}'"
    type_ = entry.get("type")
    causality = entry.get("causality")
    if not (_choice(type_, TYPES, f"{what}: type", entry.line, problems)
            and _choice(causality, tuple(VARIABILITIES), f"{what}: causality", entry.line, problems)):
        return None
    allowed, default_real, default_other = VARIABILITIES[causality]
    variability = entry.get("variability", default_real if type_ == "real" else default_other)
    if _choice(variability, allowed, f"{what}: variability", entry.line, problems):
        if variability == "continuous" and type_ != "real":
            problems.append((entry.line, f"{what}: only real variables can be continuous"))
    start = entry.get("start")
    if start is None and causality in ("parameter", "input"):
        problems.append((entry.line, f"{what}: a {causality} needs a start value"))
    elif start is not None:
        start = _check_value(start, type_, f"{what}: start", entry.line, problems)
    bounds = {}
    for key in ("min", "max"):
        if key in entry:
            if type_ not in ("real", "int"):
                problems.append((entry.line, f"{what}: {key} is only allowed for real and int"))
            else:
                bounds[key] = _check_value(entry[key], type_, f"{what}: {key}", entry.line, problems)
    low, high = bounds.get("min"), bounds.get("max")
    if low is not None and high is not None and low > high:
        problems.append((entry.line, f"{what}: min {low} is greater than max {high}"))
    if isinstance(start, (int, float)) and not isinstance(start, bool):
        if (low is not None and start < low) or (high is not None and start > high):
            problems.append((entry.line, f"{what}: start {start} is outside [{low}, {high}]"))
    unit = entry.get("unit")
    if unit is not None and (type_ != "real" or not isinstance(unit, str) or not unit):
        problems.append((entry.line, f"{what}: unit must be a non-empty string on a real variable"))
    if len(problems) > count:
        return None
    return Variable(name, type_, causality, variability, start, str(entry.get("description", "")),
                    unit, low, high, vr)


def _is_finite_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _check_value(value, type_, what, line, problems):
    if type_ == "real" and _is_finite_number(value):
        return float(value)
    if type_ == "int" and isinstance(value, int) and not isinstance(value, bool):
        if INT32_MIN <= value <= INT32_MAX:
            return value
        problems.append((line, f"{what} {value} does not fit in 32 bits"))
        return None
    if type_ == "bool" and isinstance(value, bool):
        return value
    if type_ == "string" and isinstance(value, str):
        return value
    expected = {"real": "a finite number", "int": "an integer", "bool": "true or false", "string": "a string"}
    problems.append((line, f"{what} {value!r} is not {expected[type_]}"))
    return None


def _check_state(entries, line, variable_names, problems):
    if not isinstance(entries, list):
        problems.append((line, "state must be a list"))
        return []
    fields, seen = [], set()
    for entry in entries:
        if not isinstance(entry, _Entry):
            problems.append((line, f"each state field must be a mapping, got {entry!r}"))
            continue
        _unknown_keys(entry, STATE_KEYS, f"state field '{entry.get('name')}'", problems)
        name, type_ = entry.get("name"), entry.get("type")
        ok = _check_identifier(name, "state field name", entry.line, problems)
        ok = _choice(type_, tuple(STATE_TYPES), f"state field '{name}': type", entry.line, problems) and ok
        if ok and name in seen:
            problems.append((entry.line, f"state field '{name}' is declared twice"))
        elif ok:
            seen.add(name)
            fields.append(StateField(name, type_, str(entry.get("description", ""))))
    return fields


# ---------------------------------------------------------------- modelDescription.xml


def _xml_value(value):
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value) if isinstance(value, float) else str(value)


def _initial(variable):
    """The FMI 'initial' attribute, or None where the standard forbids or implies it."""
    if variable.causality in ("output", "local"):
        return "calculated" if variable.start is None else "exact"
    return None


def model_description(model, fmi_version):
    """The modelDescription.xml of model for FMI 2 or 3, as bytes."""
    root = ET.Element("fmiModelDescription")
    root.set("fmiVersion", "2.0" if fmi_version == 2 else "3.0")
    root.set("modelName", model.name)
    root.set("guid" if fmi_version == 2 else "instantiationToken", model.token)
    if model.description:
        root.set("description", model.description)
    root.set("generationTool", GENERATION_TOOL)
    root.set("variableNamingConvention", "flat")
    if fmi_version == 2:
        root.set("numberOfEventIndicators", "0")
    cosim = ET.SubElement(root, "CoSimulation", modelIdentifier=model.name,
                          canHandleVariableCommunicationStepSize="true")
    if fmi_version == 2:
        # The framework allocates with calloc/free, never through the importer's callbacks.
        cosim.set("canNotUseMemoryManagementFunctions", "true")
    units = sorted({v.unit for v in model.variables if v.unit})
    if units:
        unit_definitions = ET.SubElement(root, "UnitDefinitions")
        for unit in units:
            ET.SubElement(unit_definitions, "Unit", name=unit)
    categories = ET.SubElement(root, "LogCategories")
    for name, description in LOG_CATEGORIES:
        ET.SubElement(categories, "Category", name=name, description=description)
    if model.default_experiment:
        ET.SubElement(root, "DefaultExperiment",
                      {EXPERIMENT_KEYS[k]: _xml_value(float(v)) for k, v in model.default_experiment.items()})
    variables = ET.SubElement(root, "ModelVariables")
    for variable in model.variables:
        (_fmi2_variable if fmi_version == 2 else _fmi3_variable)(variables, variable)
    outputs = [v for v in model.variables if v.causality == "output"]
    initial_unknowns = [v for v in outputs if _initial(v) == "calculated"]
    structure = ET.SubElement(root, "ModelStructure")
    if fmi_version == 2:
        # FMI 2 addresses variables by 1-based position in ModelVariables, which is vr + 1 here.
        for tag, members in (("Outputs", outputs), ("InitialUnknowns", initial_unknowns)):
            if members:
                group = ET.SubElement(structure, tag)
                for variable in members:
                    ET.SubElement(group, "Unknown", index=str(variable.vr + 1))
    else:
        for tag, members in (("Output", outputs), ("InitialUnknown", initial_unknowns)):
            for variable in members:
                ET.SubElement(structure, tag, valueReference=str(variable.vr))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True) + b"\n"


def _common_attributes(variable):
    attributes = {"name": variable.name, "valueReference": str(variable.vr)}
    if variable.description:
        attributes["description"] = variable.description
    attributes["causality"] = variable.causality
    attributes["variability"] = variable.variability
    if _initial(variable):
        attributes["initial"] = _initial(variable)
    return attributes


def _type_attributes(variable, with_start):
    attributes = {}
    if variable.unit:
        attributes["unit"] = variable.unit
    for key in ("min", "max"):
        if getattr(variable, key) is not None:
            attributes[key] = _xml_value(getattr(variable, key))
    if with_start and variable.start is not None:
        attributes["start"] = _xml_value(variable.start)
    return attributes


def _fmi2_variable(parent, variable):
    element = ET.SubElement(parent, "ScalarVariable", _common_attributes(variable))
    ET.SubElement(element, FMI2_ELEMENTS[variable.type], _type_attributes(variable, with_start=True))


def _fmi3_variable(parent, variable):
    is_string = variable.type == "string"
    attributes = _common_attributes(variable)
    attributes.update(_type_attributes(variable, with_start=not is_string))
    element = ET.SubElement(parent, FMI3_ELEMENTS[variable.type], attributes)
    if is_string and variable.start is not None:
        ET.SubElement(element, "Start", value=variable.start)


# ---------------------------------------------------------------- C description


def _c_string(text):
    """A C99 string literal; '?' is escaped because -std=c99 enables trigraphs."""
    out = []
    for byte in text.encode("utf-8"):
        char = chr(byte)
        if char in '"\\?':
            out.append("\\" + char)
        elif 0x20 <= byte < 0x7F:
            out.append(char)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def _c_value(value, type_):
    if type_ == "bool":
        return "true" if value else "false"
    if type_ == "string":
        return _c_string(value)
    if type_ == "real":
        return repr(float(value))
    return str(int(value)) if value != INT32_MIN else "INT32_MIN"


def _c_comment(text):
    return text.replace("*/", "* /").replace("\n", " ")


def _enum_name(camel):
    return "LOG_" + re.sub(r"(?<!^)(?=[A-Z])", "_", camel[3:]).upper()


def c_header(model):
    """model_description.h: value references, the variable and state structs, log categories."""
    lines = [
        f"/* Generated by {GENERATION_TOOL} from {_c_comment(model.source)}; do not edit. */",
        "#ifndef MODEL_DESCRIPTION_H",
        "#define MODEL_DESCRIPTION_H",
        "",
        "#include <stdbool.h>",
        "#include <stdint.h>",
        "",
        '#include "variable_info.h"',
        "",
        f"#define MODEL_IDENTIFIER {_c_string(model.name)}",
        f"#define MODEL_TOKEN {_c_string(model.token)}",
        f"#define VARIABLE_COUNT {len(model.variables)}u",
        "",
        "typedef enum {",
    ]
    lines += [f"    VR_{v.name.upper()} = {v.vr}," for v in model.variables]
    lines += ["} ValueReference;", "", "/* Every variable except time, which the framework keeps. */", "typedef struct {"]
    for variable in model.variables[1:]:
        unit = f" [{variable.unit}]" if variable.unit else ""
        comment = _c_comment(f"{variable.causality}{unit}: {variable.description}".rstrip(": "))
        lines.append(f"    {C_TYPES[variable.type]}{'' if variable.type == 'string' else ' '}{variable.name}; /* {comment} */")
    lines += ["} ModelVariables;", "", "/* Private state of the model, zeroed on instantiate and reset. */",
              "typedef struct {"]
    for field in model.state:
        comment = f" /* {_c_comment(field.description)} */" if field.description else ""
        lines.append(f"    {STATE_TYPES[field.type]} {field.name};{comment}")
    if not model.state:
        lines.append("    char unused; /* C99 forbids empty structs */")
    lines += ["} ModelState;", "", "typedef enum {"]
    lines += [f"    {_enum_name(name)}," for name, _ in LOG_CATEGORIES]
    lines += [
        "    LOG_CATEGORY_COUNT",
        "} LogCategory;",
        "",
        "extern const VariableInfo MODEL_VARIABLES[VARIABLE_COUNT];",
        "extern const char *const LOG_CATEGORY_NAMES[LOG_CATEGORY_COUNT];",
        "",
        "#endif",
        "",
    ]
    return "\n".join(lines)


def c_source(model):
    """model_description.c: the variable table the framework's get/set/reset are driven by."""
    lines = [
        f"/* Generated by {GENERATION_TOOL} from {_c_comment(model.source)}; do not edit. */",
        "#include <stddef.h>",
        "",
        '#include "model_description.h"',
        "",
        "const VariableInfo MODEL_VARIABLES[VARIABLE_COUNT] = {",
    ]
    for variable in model.variables:
        fields = [
            f".name = {_c_string(variable.name)}",
            f".type = {C_TYPE_TAGS[variable.type]}",
            f".causality = CAUSALITY_{variable.causality.upper()}",
            f".variability = VARIABILITY_{variable.variability.upper()}",
        ]
        if variable.vr:
            fields.append(f".offset = offsetof(ModelVariables, {variable.name})")
        if variable.start is not None:
            fields += [".has_start = true",
                       f".start = {{.{C_START_MEMBER[variable.type]} = {_c_value(variable.start, variable.type)}}}"]
        for key in ("min", "max"):
            if getattr(variable, key) is not None:
                fields += [f".has_{key} = true", f".{key} = {_c_value(float(getattr(variable, key)), 'real')}"]
        lines.append(f"    [VR_{variable.name.upper()}] = {{{', '.join(fields)}}},")
    lines += ["};", "", "const char *const LOG_CATEGORY_NAMES[LOG_CATEGORY_COUNT] = {"]
    lines += [f"    [{_enum_name(name)}] = {_c_string(name)}," for name, _ in LOG_CATEGORIES]
    lines += ["};", ""]
    return "\n".join(lines)


# ---------------------------------------------------------------- command line


def generate(model_dir, out_dir):
    """Write src/model_description.{h,c} and fmi<v>/modelDescription.xml for both FMI versions under out_dir."""
    model = load(model_dir)
    out = Path(out_dir)
    outputs = {
        out / "src" / "model_description.h": c_header(model).encode(),
        out / "src" / "model_description.c": c_source(model).encode(),
        out / "fmi2" / "modelDescription.xml": model_description(model, 2),
        out / "fmi3" / "modelDescription.xml": model_description(model, 3),
    }
    for path, content in outputs.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(content)


def list_fmus(models_dir):
    """Names '<model>-fmi<v>' of every FMU the models in models_dir ask for."""
    names, problems = [], []
    for model_dir in sorted(p.parent for p in Path(models_dir).glob("*/model.yaml")):
        try:
            model = load(model_dir)
        except DescriptionError as error:
            problems += error.problems
            continue
        names += [f"{model.name}-fmi{version}" for version in model.fmi_versions]
    if problems:
        raise DescriptionError(problems)
    return names


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--list", metavar="MODELS_DIR", help="print the FMUs the models in MODELS_DIR ask for")
    parser.add_argument("model_dir", nargs="?", help="directory holding model.yaml")
    parser.add_argument("out_dir", nargs="?", help="build directory of this model")
    args = parser.parse_args(argv)
    try:
        if args.list:
            print(" ".join(list_fmus(args.list)))
        elif args.model_dir and args.out_dir:
            generate(args.model_dir, args.out_dir)
        else:
            parser.error("give MODEL_DIR OUT_DIR, or --list MODELS_DIR")
    except DescriptionError as error:
        print(str(error), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
