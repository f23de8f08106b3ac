"""Write a model's modelDescription.xml (FMI 2.0 and 3.0) and its C description from its model.yaml."""

import argparse
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

sys.dont_write_bytecode = True  # keep __pycache__ out of the source tree; only $(BUILD) gets outputs
from description import INT32_MIN, DescriptionError, load  # noqa: E402

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

# C declaration of a variable, with {} for its name.
C_DECLARATIONS = {"real": "double {}", "int": "int32_t {}", "bool": "bool {}", "string": "char *{}"}
C_STATE_TYPES = {"real": "double", "int32": "int32_t", "int64": "int64_t", "bool": "bool"}
C_STATE_TAGS = {"real": "STATE_REAL", "int32": "STATE_INT32", "int64": "STATE_INT64", "bool": "STATE_BOOL"}
C_TYPE_TAGS = {"real": "VAR_REAL", "int": "VAR_INT", "bool": "VAR_BOOL", "string": "VAR_STRING"}
C_START_MEMBER = {"real": "real", "int": "integer", "bool": "boolean", "string": "string"}
FMI2_ELEMENTS = {"real": "Real", "int": "Integer", "bool": "Boolean", "string": "String"}
FMI3_ELEMENTS = {"real": "Float64", "int": "Int32", "bool": "Boolean", "string": "String"}
EXPERIMENT_ATTRIBUTES = {"start_time": "startTime", "stop_time": "stopTime", "step_size": "stepSize",
                         "tolerance": "tolerance"}


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
    # framework/state.c copies and serializes an instance's whole state (checkpoints of a run).
    state = "FMUstate" if fmi_version == 2 else "FMUState"
    cosim.set(f"canGetAndSet{state}", "true")
    cosim.set(f"canSerialize{state}", "true")
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
                      {EXPERIMENT_ATTRIBUTES[k]: _xml_value(float(v)) for k, v in model.default_experiment.items()})
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
    """Text safe inside /* */: no end marker, no newline, no trigraph."""
    return text.replace("*/", "* /").replace("\n", " ").replace("??", "? ?")


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
        f"#define STATE_FIELD_COUNT {len(model.state)}u",
        "",
        "typedef enum {",
    ]
    lines += [f"    VR_{v.name.upper()} = {v.vr}," for v in model.variables]
    lines += ["} ValueReference;", "", "/* Every variable except time, which the framework keeps. */",
              "typedef struct {"]
    for variable in model.variables[1:]:
        unit = f" [{variable.unit}]" if variable.unit else ""
        comment = _c_comment(f"{variable.causality}{unit}: {variable.description}".rstrip(": "))
        lines.append(f"    {C_DECLARATIONS[variable.type].format(variable.name)}; /* {comment} */")
    lines += ["} ModelVariables;", "", "/* Private state of the model, zeroed on instantiate and reset. */",
              "typedef struct {"]
    for field in model.state:
        comment = f" /* {_c_comment(field.description)} */" if field.description else ""
        lines.append(f"    {C_STATE_TYPES[field.type]} {field.name};{comment}")
    if not model.state:
        lines.append("    char unused; /* C99 forbids empty structs */")
    lines += ["} ModelState;", "", "typedef enum {"]
    lines += [f"    {_enum_name(name)}," for name, _ in LOG_CATEGORIES]
    lines += [
        "    LOG_CATEGORY_COUNT",
        "} LogCategory;",
        "",
        "extern const VariableInfo MODEL_VARIABLES[VARIABLE_COUNT];",
        "/* The fields of ModelState, ended by one with a NULL name (a model may have none). */",
        "extern const StateFieldInfo MODEL_STATE_FIELDS[STATE_FIELD_COUNT + 1u];",
        "extern const char *const LOG_CATEGORY_NAMES[LOG_CATEGORY_COUNT];",
        "",
        "#endif",
        "",
    ]
    return "\n".join(lines)


def c_source(model):
    """model_description.c: the variable table the framework's get/set/reset are driven by, and the
    state table its FMU-state calls copy and serialize by."""
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
    lines += ["};", "", "const StateFieldInfo MODEL_STATE_FIELDS[STATE_FIELD_COUNT + 1u] = {"]
    for field in model.state:
        lines.append(f"    {{.name = {_c_string(field.name)}, .type = {C_STATE_TAGS[field.type]}, "
                     f".offset = offsetof(ModelState, {field.name})}},")
    lines += ["    {.name = NULL},", "};", "", "const char *const LOG_CATEGORY_NAMES[LOG_CATEGORY_COUNT] = {"]
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
