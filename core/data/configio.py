"""YAML loading whose errors name the file and the field.

The loader is PyYAML's safe one (no tags that build objects), with two changes users expect:
numbers written as people write them are numbers (`1e-3` is a float, as in YAML 1.2, not the
string YAML 1.1 makes of it), and a key given twice in one mapping is an error naming its line
(a copy-paste slip would otherwise remap another material without a word)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, TypeVar

import yaml
from pydantic import BaseModel, ValidationError

from .errors import ConfigError

M = TypeVar("M", bound=BaseModel)


class WrongKindError(ConfigError):
    """The file is of another kind than the one expected (a material where a scene was)."""

_FLOAT = re.compile(r"""^[-+]?(?:(?:[0-9][0-9_]*)(?:\.[0-9_]*)?|\.[0-9_]+)(?:[eE][-+]?[0-9]+)?$
                        |^[-+]?\.(?:inf|Inf|INF)$|^\.(?:nan|NaN|NAN)$""", re.X)


_DOTTED = re.compile(r"^[a-z_][a-z0-9_]*(\.[a-z_][a-z0-9_]*)*$")


class _Loader(yaml.SafeLoader):
    def compose_node(self, parent, index):
        # Aliases (and the merge keys built on them) are refused: a few hundred bytes of nested
        # aliases expand to gigabytes ("billion laughs"), and no file of this tool needs them.
        if self.check_event(yaml.events.AliasEvent):
            event = self.peek_event()
            raise yaml.composer.ComposerError(None, None, "aliases (*name) and merge keys (<<) are not supported: "
                                              "write the values out", event.start_mark)
        return super().compose_node(parent, index)

    def construct_mapping(self, node, deep=False):
        seen: dict[Any, int] = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            line = key_node.start_mark.line + 1
            try:
                if key in seen:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"{_short(key)} is given twice (first on line {seen[key]}): keep one",
                        key_node.start_mark)
                seen[key] = line
            except TypeError:
                continue  # an unhashable key: the safe constructor reports it
        return super().construct_mapping(node, deep)


def _short(value: Any, n: int = 80) -> str:
    text = repr(value)
    return text if len(text) <= n else text[:n] + "…"


# Floats as YAML 1.2 reads them (PyYAML's 1.1 rule wants a dot: 1e-3 would be a string).
_Loader.yaml_implicit_resolvers = {k: list(v) for k, v in yaml.SafeLoader.yaml_implicit_resolvers.items()}
_Loader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT, list("-+0123456789."))


def read_yaml(path: str | Path) -> Any:
    p = Path(path)
    if not p.exists():
        raise ConfigError("file not found (check the path)", file=str(path))
    if p.is_dir():
        raise ConfigError("is a directory, expected a YAML file", file=str(path))
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise ConfigError("is not a text file (expected YAML in UTF-8)", file=str(path)) from None
    except OSError as exc:
        raise ConfigError(f"cannot read: {exc.strerror or exc}", file=str(path)) from None
    try:
        return yaml.load(text, Loader=_Loader)  # noqa: S506 - a SafeLoader subclass
    except RecursionError:
        raise ConfigError("malformed YAML: nested too deeply", file=str(path)) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}, column {mark.column + 1}" if mark else None
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError(f"malformed YAML: {problem}", file=str(path), field=where) from None


def validation_message(exc: ValidationError) -> tuple[str, str]:
    """First error of a pydantic ValidationError as (dotted field, message)."""
    errors = exc.errors()
    # A misspelt field also leaves a required one missing; the misspelling is the news.
    err = next((e for e in errors if e["type"] == "extra_forbidden"), errors[0])
    from .model import UNION_TAGS

    loc = err["loc"]
    field = ".".join(str(p) for i, p in enumerate(loc)
                     if not (p in UNION_TAGS and i > 0 and isinstance(loc[i - 1], int)))
    msg = err["msg"]
    if err["type"] == "extra_forbidden":
        msg = "unknown field (remove it or check its spelling)"
    elif err["type"] == "value_error":
        msg = str(err.get("ctx", {}).get("error", msg))
        # A check across fields names the one to change first: "camera.distance: ..."
        head, sep, rest = msg.partition(": ")
        if sep and not field and _DOTTED.match(head):
            field, msg = head, rest
    return field or "(top level)", msg


_ROLES = {"a result (result.json)": {"schema_version", "key"}, "a material": {"adapter", "model"},
          "an experiment": {"kind", "sweep"}, "a table spec": {"kind", "axes"},
          "a renderer definition": {"name", "command"}, "a scene": {"sphere", "camera"}}


def _role(data: dict) -> str | None:
    """What kind of file the document looks like, by the keys that only that kind has."""
    return next((role for role, keys in _ROLES.items() if keys <= set(data)), None)


def load_yaml_model(path: str | Path, model: type[M], what: str = "", context: dict | None = None) -> M:
    """A model from a YAML file. ``what`` ("a material", "an experiment", ...) names the file's
    expected kind: a file of another kind is said to be one. ``context`` goes to the validators
    (a scene resolves a map's path against its file's folder)."""
    data = read_yaml(path)
    if data is None:
        raise ConfigError(f"is empty: expected {what or 'a YAML mapping'}", file=str(path))
    if not isinstance(data, dict):
        raise ConfigError(f"expected a mapping at the top level, got {type(data).__name__}", file=str(path))
    try:
        return model.model_validate(data, context=context)
    except ValidationError as exc:
        role = _role(data)
        if what and role and role != what:
            raise WrongKindError(f"is {role} file, where {what} was expected", file=str(path)) from None
        field, msg = validation_message(exc)
        raise ConfigError(msg, file=str(path), field=field) from None
