"""``sto-harness fmu --model MODEL.toml --out DIR``: the observer/identifier FMU of a
model file, with no compiler on the user's machine.

The ModelObserver FMU (fmu/src/models/ModelObserver/model.c) is one binary for every model
file: it reads the model's equations from ``resources/model.txt`` (the term program,
:mod:`harness.model.program`).  Its modelDescription names generic scalars
(``position_1``, ``theta_3``, ...); the FMU written here is that FMU with the model's
program as its resource and a modelDescription in which the variables the model uses
carry the model's names and units, the others left out:

- inputs: each coordinate by its name (the measured position, in its unit) and each
  known input by its name;
- outputs: ``der(c)`` the velocity estimate of coordinate c and ``c_hat`` its position
  estimate, each unknown parameter by its name (in its unit), ``<name>_std`` its
  standard error and ``<name>_excitation`` the share of its regressor column the others
  do not explain (identify's excitation figure); ``observer.converged``,
  ``observer.identifier_active``, ``observer.excitation``,
  ``observer.parameters_not_excited``, ``observer.input_hold``, ``observer.coarse_inputs``;
- parameters: the observer's settings under ``observer.`` (``observer.h`` the internal
  step, ``observer.f_plus_<c>`` the gains' bound of coordinate c, ...).

The names use the flat naming convention (``der(x)`` is a plain name there), so no
model name can collide with a setting.
"""
from __future__ import annotations

import re
import zipfile
from dataclasses import dataclass
from pathlib import Path

import sympy
from lxml import etree

from ..names import plain
from ..paths import default_fmu_dir
from .model import Model
from .program import ProgramError, compile_program
from .units import quantity, si_factor

TEMPLATE = "ModelObserver"
#: The base units FMI's <BaseUnit> takes, by pint's dimension name.
_BASE_UNITS = {"[mass]": "kg", "[length]": "m", "[time]": "s", "[current]": "A",
               "[temperature]": "K", "[substance]": "mol", "[luminosity]": "cd"}
#: The generic variables that are the model's own: prefix -> what they are one of.
_PREFIXES = {"position_": "coordinates", "position_estimate_": "coordinates",
             "velocity_": "coordinates", "f_plus_": "coordinates", "input_": "inputs",
             "theta_": "parameters", "theta_std_": "parameters",
             "theta_excitation_": "parameters"}


class ExportError(ValueError):
    """The FMU cannot be written for this model (the message says why)."""


@dataclass(frozen=True)
class Limits:
    """What the ModelObserver binary takes, read from its own modelDescription."""

    coordinates: int
    inputs: int
    parameters: int


def template_fmu(fmi_version: int, folder: Path | None = None) -> Path:
    """The ModelObserver FMU of FMI version 2 or 3 that this installation ships."""
    base = Path(folder) if folder else default_fmu_dir()
    # FMI 3: build/fmi3/ beside build/fmus/ in a checkout, data/fmi3/ in a wheel
    candidates = [base / f"{TEMPLATE}.fmu"] if fmi_version == 2 else \
        [base.parent / "fmi3" / f"{TEMPLATE}.fmu", base / "fmi3" / f"{TEMPLATE}.fmu"]
    path = next((c for c in candidates if c.exists()), candidates[-1])
    if not path.exists():
        raise ExportError(f"the ModelObserver FMU (FMI {fmi_version}) is not at {path}: in a "
                          "checkout run ./build.sh fmus, else reinstall the package")
    return path


def _count(names: list[str], prefix: str) -> int:
    return sum(1 for n in names if re.fullmatch(re.escape(prefix) + r"\d+", n))


def limits_of(description: etree._Element) -> Limits:
    """The template's sizes: its generic inputs and outputs."""
    names = [v.get("name") for v in description.find("ModelVariables")]
    return Limits(_count(names, "position_"), _count(names, "input_"), _count(names, "theta_"))


def _element_index(name: str) -> tuple[str, int] | None:
    """(prefix, 0-based index) of a generic element name such as ``theta_std_3``."""
    match = re.fullmatch(r"([a-z_]+_)(\d+)", name)
    if match and match.group(1) in _PREFIXES:
        return match.group(1), int(match.group(2)) - 1
    return None


def _rename(model: Model, name: str) -> tuple[str | None, str, str]:
    """The variable's name in the model's FMU (None: left out), its unit and its
    description, for a generic variable of the template."""
    found = _element_index(name)
    if found is None:
        return f"observer.{name}", "", ""
    prefix, i = found
    owners = getattr(model, _PREFIXES[prefix])
    if i >= len(owners):
        return None, "", ""
    if _PREFIXES[prefix] == "parameters":
        p = model.parameters[i]
        return {
            "theta_": (p.name, p.unit, f"Estimate of the unknown {p.name}"),
            "theta_std_": (f"{p.name}_std", p.unit, f"Standard error of {p.name} (1 sigma)"),
            "theta_excitation_": (
                f"{p.name}_excitation", "",
                f"Share of {p.name}'s regressor column the others do not explain, 0 to 1 "
                "(below 0.001 the log does not determine it)"),
        }[prefix]
    owner = owners[i]
    unit = model.units.get(owner, "")
    per = {"velocity_": "/s", "f_plus_": "/s^2"}.get(prefix, "")
    return {
        "input_": (owner, unit, f"Known input {owner}"),
        "position_": (owner, unit, f"Measured {owner}"),
        "position_estimate_": (f"{owner}_hat", unit, f"Estimate of {owner}"),
        "velocity_": (f"der({owner})", unit + per if unit else "",
                      f"Velocity estimate of {owner}"),
        "f_plus_": (f"observer.f_plus_{owner}", unit + per if unit else "",
                    f"Bound of the nominal model's acceleration error of {owner}: the "
                    "super-twisting gains by Theorem 3.1"),
    }[prefix]


def _base_unit(unit: str) -> dict[str, str]:
    """FMI <BaseUnit> attributes of ``unit`` (exponents and factor to SI)."""
    q = quantity(unit).to_base_units()
    attributes = {}
    for dimension, power in q.dimensionality.items():
        exponent = float(power)  # type: ignore[arg-type]
        base = _BASE_UNITS.get(dimension)
        if base is None:
            raise ExportError(f"the unit {unit!r} has a dimension {dimension} FMI has no base "
                              "unit for")
        if exponent != int(exponent):
            raise ExportError(f"the unit {unit!r} has a fractional exponent")
        attributes[base] = str(int(exponent))
    if float(q.magnitude) != 1.0:
        attributes["factor"] = repr(float(q.magnitude))
    return attributes


def model_description(model: Model, template: bytes, fmi_version: int,
                      identifier: int | None) -> bytes:
    """The model's modelDescription.xml from the template's (see the module)."""
    root = etree.fromstring(template)
    limits = limits_of(root)
    for what, count, limit in (("coordinates", len(model.coordinates), limits.coordinates),
                               ("known inputs", len(model.inputs), limits.inputs),
                               ("unknown parameters", len(model.parameters), limits.parameters)):
        if count > limit:
            raise ExportError(f"the model has {count} {what}: the FMU takes at most {limit} "
                              "(identify and validate take the model as it is)")
    name = plain(Path(model.source).stem)  # XML holds no control characters
    root.set("modelName", name)
    root.set("description", "Observer and identifier of the model file "
             f"{plain(Path(model.source).name)} (super-twisting observer, LSM/MFF identifier)")
    root.set("variableNamingConvention", "flat")
    root.set("generationTool", "sto-harness fmu --model")
    variables = root.find("ModelVariables")
    kept: dict[str, str] = {}   # old name -> new name
    old_index: dict[int, int] = {}  # FMI 2: 1-based index, old -> new
    units: set[str] = set()
    new_index = 0
    for old, variable in enumerate(list(variables), start=1):
        generic = variable.get("name")
        renamed, unit, description = (generic, "", "") if generic == "time" else \
            _rename(model, generic)
        if renamed is None:
            variables.remove(variable)
            continue
        new_index += 1
        old_index[old] = new_index
        kept[generic] = renamed
        variable.set("name", renamed)
        if description:
            variable.set("description", description)
        typed = variable if fmi_version == 3 else variable[0]
        if unit:
            typed.set("unit", unit)
            units.add(unit)
        elif typed.get("unit"):
            units.add(typed.get("unit"))
        if generic == "identifier" and identifier is not None:
            typed.set("start", str(identifier))
        found = _element_index(generic)
        if found and found[0] == "f_plus_" and model.units:
            # the binary sets the bound from SI for the coordinate's unit (its resource)
            scale = si_factor(model.units[model.coordinates[found[1]]])
            typed.set("start", repr(float(typed.get("start")) / scale))
    clash = sorted({n for n in kept.values() if list(kept.values()).count(n) > 1})
    if clash:
        raise ExportError(f"the FMU's variables would share the names {', '.join(clash)}: "
                          "rename the model's names (a parameter X beside another named X_std or "
                          "X_excitation?)")
    _unit_definitions(root, units)
    _model_structure(root, fmi_version, old_index, {v.get("valueReference") for v in variables})
    etree.indent(root, space="  ")
    return etree.tostring(root, xml_declaration=True, encoding="UTF-8")


def _unit_definitions(root: etree._Element, units: set[str]) -> None:
    definitions = root.find("UnitDefinitions")
    if definitions is None:
        definitions = etree.Element("UnitDefinitions")
        root.insert(list(root).index(root.find("LogCategories")), definitions)
    for child in list(definitions):
        definitions.remove(child)
    for unit in sorted(units):
        element = etree.SubElement(definitions, "Unit", name=unit)
        etree.SubElement(element, "BaseUnit", _base_unit(unit))


def _model_structure(root: etree._Element, fmi_version: int, old_index: dict[int, int],
                     references: set[str | None]) -> None:
    structure = root.find("ModelStructure")
    if fmi_version == 3:
        for element in list(structure):
            if element.get("valueReference") not in references:
                structure.remove(element)
        return
    for group in structure:
        for unknown in list(group):
            index = int(unknown.get("index"))
            if index in old_index:
                unknown.set("index", str(old_index[index]))
            else:
                group.remove(unknown)


def build_fmu(model: Model, destination: Path, fmi_version: int = 2,
              identifier: int | None = None, template: Path | None = None) -> None:
    """Writes the model's FMU to ``destination`` (a file name; written in one go)."""
    if all(sympy.sympify(eq.known) == 0 for eq in model.equations):
        raise ExportError("no equation has a known side (an input or a known term): the "
                          "equations are homogeneous in the unknowns, which a log then fixes "
                          "only up to a common scale; give one unknown as a constant "
                          "([constants]) or add the input that drives the system")
    try:
        program = compile_program(model)
    except ProgramError as error:
        raise ExportError(str(error)) from None
    options = [f"identifier {identifier}"] if identifier is not None else []
    if model.input_timing == "held":  # the window's input kernel takes the hold
        options.append("inputs_held 1")
    if options:
        program = program.replace("\nentry ", "\n" + "\n".join(options) + "\nentry ", 1)
    source = template or template_fmu(fmi_version)
    with zipfile.ZipFile(source) as fmu:
        xml = model_description(model, fmu.read("modelDescription.xml"), fmi_version,
                                identifier)
        with zipfile.ZipFile(destination, "w", zipfile.ZIP_DEFLATED) as out:
            out.writestr("modelDescription.xml", xml)
            out.writestr("resources/model.txt", program)
            for info in fmu.infolist():
                # the template's own reference results are the template's model's
                if info.filename in ("modelDescription.xml", "resources/model.txt") or \
                        info.filename.startswith("extra/org.fmi-standard.fmi-ls-ref") or \
                        info.filename == "documentation/fmi-ls-ref.txt":
                    continue
                out.writestr(info, fmu.read(info.filename))


def fmu_command(args) -> int:
    """``fmu --model MODEL.toml --out DIR [--fmi-version 2|3] [--identifier lsm|mff]``."""
    import sys

    from ..outputs import Outputs, shown
    from .errors import ModelFileError
    from .reader import read_model

    identifier = {None: None, "lsm": 1, "mff": 2}[args.identifier]
    try:
        model = read_model(args.model)
        name = f"{Path(model.source).stem}.fmu"
        with Outputs(args.out, "fmu", inputs=[args.model], names=[name]) as outputs:
            template = template_fmu(args.fmi_version, getattr(args, "fmu_dir", None))
            build_fmu(model, outputs.file(name), args.fmi_version, identifier, template)
    except (ModelFileError, ExportError) as error:  # an OutputError names the command
        print(f"harness fmu: {error}", file=sys.stderr)
        return 2
    print(f"wrote {shown(outputs.written[0])} (FMI {args.fmi_version}.0 co-simulation): inputs "
          f"{', '.join((*model.coordinates, *model.inputs))}; outputs "
          f"{', '.join(f'der({c})' for c in model.coordinates)}, "
          f"{', '.join(p.name for p in model.parameters)} with their _std and _excitation")
    return 0
