"""`remap convert`: a library's materials, each an ordinary job through the store and the runner,
written back as one native library per target, with a report (index.html).

The output folder holds `materials/<slot>/` (each material's result), the libraries the target's
writers make (`library.blend`, `library.xml`, `library.mtlx`), `convert.json` (every material:
converted, failed or unsupported, and why) and `index.html`. Rerun after an interruption and
only the unfinished materials run; change an input and only what changed runs again."""

from __future__ import annotations

import hashlib
import json
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..data.appearance import Appearance
from ..data.atomic import write_bytes_atomic, write_json_atomic
from ..data.errors import ConfigError, RemapError
from ..data.scene import ProbeScene
from ..data.schemas import Material
from ..data.settings import Settings
from ..data.textures import Texture
from ..host.plugins import AdapterRegistry
from ..host.protocol import ModelChoice
from ..job.execute import IMAGES, AdapterPool
from ..job.job import Job, Target, Where, model_of, resolve, source_model
from ..run.executors import Workers
from ..run.runner import Done, Runner, Task
from ..run.store import Store, owned
from ..tables import Table, TableMap
from ..tables.lookup import Answer
from ..textured import texture_result
from .alternatives import Tried, advise, keep_best, retries
from .formats import Converted, Entry, Formats
from .records import ConvertSummary, ItemStatus, MaterialRow, TriedModel


@dataclass(frozen=True)
class Destination:
    adapter: str
    model: str | None
    """None: the adapter chooses per material (`Adapter.model_for`)."""

    @classmethod
    def parse(cls, text: str, registry: AdapterRegistry) -> Destination:
        adapter, _, model = text.partition(":")
        adapter = registry.resolve(adapter, field_name="--to")  # a name, or a renderer definition file
        entry = registry.get(adapter, field_name="--to")
        if model and model not in entry.models:
            raise ConfigError(f"adapter {adapter!r} has no model {model!r} (models: {', '.join(sorted(entry.models))})",
                              field="--to")
        return cls(adapter, model or None)


@dataclass
class Item:
    """One material of the library and what became of it."""

    entry: Entry
    slot: str = ""
    model: str = ""
    why: str = ""
    """Why this target model (when the adapter chose it)."""
    task: Task | None = None
    done: Done | None = None
    failure: str = ""
    flattened: bool = False
    """A textured material no table maps: converted with its textures' constants (said on its line)."""
    look: Appearance | None = None
    """The source read in neutral terms, where the adapter chose the model from it (`model_for`)."""
    candidates: list[ModelChoice] = field(default_factory=list)
    """A material with no reading: the target adapter's models it is fitted to (`Adapter.candidates`), the
    first fitted, the others where it comes back a mismatch or unreliable."""
    tried: list[Tried] = field(default_factory=list)
    """Every model fitted for it, the kept one among them, where more than one was (`core.library.alternatives`)."""

    @property
    def status(self) -> ItemStatus:
        if self.entry.problem:
            return ItemStatus.FAILED if self.entry.unreadable else ItemStatus.UNSUPPORTED
        if self.failure or (self.done is not None and self.done.report is None):
            return ItemStatus.FAILED
        return ItemStatus(self.done.report.verdict) if self.done is not None else ItemStatus.PENDING

    @property
    def reason(self) -> str:
        return self.entry.problem or self.failure or (self.done.error if self.done is not None else "")


@dataclass(frozen=True)
class Conversion:
    """A library's conversion, built once every material is done and its libraries are written."""

    items: list[Item]
    destination: Destination
    libraries: list[Path]
    library_notes: list[str]
    seconds: float
    where: str

    @property
    def failed(self) -> list[Item]:
        return [i for i in self.items if i.status in (ItemStatus.FAILED, ItemStatus.UNSUPPORTED)]


def slot_of(name: str) -> str:
    """A folder name for a material: readable, and unique even where names differ only in
    characters a folder name cannot hold."""
    safe = re.sub(r"[^A-Za-z0-9._-]+", "_", name).strip("._")[:48] or "material"
    return f"{safe}-{hashlib.sha1(name.encode()).hexdigest()[:6]}"


@dataclass(frozen=True)
class TableUse:
    """A remap table given to convert (`--table`), read once."""

    file: str
    table: Table
    tmap: TableMap


def plan(entries: list[Entry], dest: Destination, registry: AdapterRegistry, adapters: AdapterPool,
         scene: ProbeScene, settings: Settings, tables: list[TableUse] = ()) -> list[Item]:
    """Each material's target model and job, checked before any render; what cannot be checked
    (out of bounds, no model to choose) is that material's failure, not the run's. A textured
    material goes through a table that maps it (texel by texel), else converts with its constants."""
    items = []
    for e in entries:
        item = Item(e, slot_of(e.name))
        if e.material is not None:
            try:
                if not (e.material.textures and _through_table(item, dest, registry, scene, settings, list(tables))):
                    _prepare(item, dest, registry, adapters, scene, settings)
            except RemapError as exc:
                item.failure = str(exc)
        items.append(item)
    return items


def _through_table(item: Item, dest: Destination, registry: AdapterRegistry, scene: ProbeScene, settings: Settings,
                   tables: list[TableUse]) -> bool:
    """A textured material's job through the table that maps it to the destination with the least
    error its direct fits reach at the textures' mean, under the probe light (held-out lights are
    judged in the result's verdict, not here): a lookup there, remapped texel by texel. False (the
    textures' constants are used, and the material's notes say why) when no table does."""
    e, src = item.entry, item.entry.material
    answers, why = _table_answers(e, src, dest, registry, tables)
    if not answers:
        ruled = _by_rule(e, registry, tables)
        if ruled is not None:  # a table of the model the source's own format maps it to by a fixed rule
            got, because = _table_answers(e, ruled[0], dest, registry, tables)
            if got:
                src, answers = ruled[0], got
                item.entry = e.model_copy(update={"material": src, "notes": [*e.notes, ruled[1]]})
            else:
                why = because
    if not answers:
        inputs = ", ".join(sorted(src.textures))
        said = (f"textured inputs ({inputs}): a uniform material fitted to the source as its renderer renders it, "
                f"starting from the images' means: {why}") if src.native is not None else \
            f"textured inputs ({inputs}) converted with their constant values: {why}"
        item.entry = e.model_copy(update={"notes": [*e.notes, said], "material": src.model_copy(update={"textures": {}})})
        item.flattened = True
        return False
    use, answer = min(answers, key=lambda ua: (ua[1].lookup.expected_error is None, ua[1].lookup.expected_error or 0.0))
    t = use.table
    # The texel-by-texel remap renders the reading's model with its maps; its uniform job, the reading at the maps' means.
    mean = src.model_copy(update={"params": {**src.params, **answer.values}, "native": None})
    job = Job(source=mean, target=t.spec.target, scene=scene, settings=settings, label=f"{e.file}: {e.name}",
              lookup=answer.lookup.model_copy(update={"file": use.file}))
    where = Where(source_file=e.file, params_prefix=f"{e.name}: params", target_file=use.file,
                  target_prefix="target.", fix_prefix="target.fix", command_line=False)
    item.model = t.spec.target.model
    item.why = f"textured: remapped texel by texel through the table {t.name!r}"
    if len(answers) > 1:
        others = ", ".join(f"{u.table.name!r} ({u.table.spec.target.model}) {_pct(a.lookup.expected_error)}"
                           for u, a in answers if u is not use)
        item.why += (f" (its fits reach {_pct(answer.lookup.expected_error)} at the textures' mean, under the "
                     f"probe light; the other tables': {others})")
    item.task = Task(item.slot, resolve(job, registry, where, textured=texture_result), e.name)
    return True


def _by_rule(e: Entry, registry: AdapterRegistry, tables: list[TableUse]):
    """A textured material as another model's, by the fixed rule its format defines (`Model.rule_for`),
    where a given table maps that model and an image drives at least one input the rule takes as it is
    (any other image is its mean, said): (the material, a note saying so), or None."""
    src = e.material
    own = model_of(registry, src.adapter, src.model, e.file, f"{e.name}: ")
    params = own.complete(src.params, file=e.file, prefix=f"{e.name}: params")
    for use in tables:
        s = use.table.spec.source
        if (s.adapter, s.model) == (src.adapter, src.model) or s.adapter not in registry.names() \
                or s.model not in registry.get(s.adapter).models:
            continue
        rule = own.rule_for(registry.get(s.adapter).models[s.model], params)
        renamed = {mine: theirs for theirs, mine in (rule.inputs.items() if rule else ())}
        if rule is None or not set(src.textures) & set(renamed):
            continue
        material = Material(adapter=s.adapter, model=s.model, name=src.name, params=dict(rule.params),
                            textures={renamed[k]: t for k, t in src.textures.items() if k in renamed})
        loose = sorted(set(src.textures) - set(renamed))
        return material, (f"read as {s.adapter}:{s.model} by the fixed rule ({rule.name}) to go through a table, "
                          f"which maps that model: the texel-by-texel remap and its check render the rule's "
                          f"{s.model}, not this {src.model}" + (
                              f"; images the rule does not take as they are ({', '.join(loose)}) are their "
                              "means" if loose else ""))
    return None


def _pct(error: float | None) -> str:
    return "an unknown error" if error is None else f"{error:.1%}"


def _table_answers(e: Entry, src, dest: Destination, registry: AdapterRegistry,
                   tables: list[TableUse]) -> tuple[list[tuple[TableUse, Answer]], str]:
    """Each given table that maps this textured material to the destination, with its lookup at the
    textures' mean; and, when none does, why (the last table's reason)."""
    from ..tables.lookup import axis_values, look_up
    from ..tables.texels import mean_values, read_inputs

    spec = registry.get(src.adapter).models[src.model]
    why = f"no --table maps {src.adapter}:{src.model} to {dest.adapter}"
    answers = []
    means: dict[tuple[str, ...], dict] = {}  # the images read once for tables of the same axes
    for use in tables:
        t = use.table
        if (t.spec.source.adapter, t.spec.source.model, t.spec.target.adapter) != (src.adapter, src.model,
                                                                                   dest.adapter):
            continue
        if dest.model is not None and dest.model != t.spec.target.model:
            why = f"the table {t.name!r} maps to {t.spec.target.model}, not {dest.model}"
            continue
        try:
            axis_values(t, src, spec, e.file, prefix=f"{e.name}: params")
            loose = sorted(set(src.textures) - set(t.spec.axes))
            if loose:
                raise ConfigError(f"its axes are {', '.join(t.spec.axes)}, and {', '.join(loose)} is an image")
        except ConfigError as exc:
            why = f"the table {t.name!r} does not map it: {exc}"
            continue
        axes = tuple(t.spec.axes)
        if axes not in means:  # a broken image fails the material, said
            means[axes] = mean_values(read_inputs(t, src, spec, e.file))
        answers.append((use, look_up(t, use.tmap, means[axes])))
    return answers, why


def _prepare(item: Item, dest: Destination, registry: AdapterRegistry, adapters: AdapterPool, scene: ProbeScene,
             settings: Settings) -> None:
    e, src = item.entry, item.entry.material
    fix: dict = {}
    item.model = dest.model or ""
    if src.adapter == dest.adapter and src.model:
        if dest.model is None:
            item.model, item.why = src.model, "its own model (the source is already this adapter's)"
        _task(item, dest, fix, registry, scene, settings)
        return
    model = source_model(registry, src, e.file, f"{e.name}: ")
    item.look = model.appearance(model.complete(src.params, file=e.file, prefix=f"{e.name}: params"))
    if dest.model is None:
        choice = adapters[dest.adapter].model_for(item.look) if item.look is not None else None
        if item.look is None and src.native is not None:  # no reading: the adapter's candidates, best kept
            item.candidates = adapters[dest.adapter].candidates()
            choice = item.candidates[0] if item.candidates else None
        if choice is None:
            raise ConfigError(f"adapter {dest.adapter!r} cannot choose a model for it: give --to "
                              f"{dest.adapter}:MODEL (models: {', '.join(sorted(registry.get(dest.adapter).models))})")
        item.model, fix, item.why = choice.model, dict(choice.fix), choice.why
    _task(item, dest, fix, registry, scene, settings)


def _task(item: Item, dest: Destination, fix: dict, registry: AdapterRegistry, scene: ProbeScene,
          settings: Settings) -> None:
    e = item.entry
    title = e.name if not item.flattened else f"{e.name} (textured: a uniform material fitted to its rendering)" \
        if e.material.native is not None else f"{e.name} (its textures as constants: no table maps it)"
    item.task = model_task(item, item.slot, dest.adapter, item.model, fix, title, registry, scene, settings)


def model_task(item: Item, slot: str, adapter: str, model: str, fix: dict, title: str, registry: AdapterRegistry,
               scene: ProbeScene, settings: Settings) -> Task:
    """The job of fitting this material to one model of the target, in ``slot``."""
    e = item.entry
    job = Job(source=e.material, target=Target(adapter=adapter, model=model, fix=fix), scene=scene,
              settings=settings, label=f"{e.file}: {e.name}")
    where = Where(source_file=e.file, params_prefix=f"{e.name}: params", target_file=None, target_prefix="--to ")
    return Task(slot, resolve(job, registry, where), title)


def convert(entries: list[Entry], dest: Destination, out: str | Path, registry: AdapterRegistry, formats: Formats,
            workers: Workers, adapters: AdapterPool, *, scene: ProbeScene, settings: Settings,
            quiet: bool = False, tables: list[TableUse] = (), events: str | Path | None = None) -> Conversion:
    from .html import write_index

    t0 = time.perf_counter()
    items = plan(entries, dest, registry, adapters, scene, settings, tables)
    with owned(out) as folder:
        runnable = [i for i in items if i.task is not None]
        runner = Runner(Store(folder / "materials"), workers, adapters,
                        quiet=quiet, stop_on_error=False, line=_line if events is None else _recorded(Path(events)))
        for item, done in zip(runnable, runner.run([i.task for i in runnable])):
            item.done = done
        second = [] if dest.model is not None else retries(
            runnable, adapters[dest.adapter],
            lambda item, slot, choice, title: model_task(item, slot, dest.adapter, choice.model, dict(choice.fix),
                                                         title, registry, scene, settings))
        if second:
            for (item, choice, _), done in zip(second, runner.run([t for _, _, t in second])):
                item.tried.append(Tried.of(choice, done))
            for item in {id(i): i for i, _, _ in second}.values():
                keep_best(item)
        for item in runnable:
            advise(item, registry.get(dest.adapter).models[item.model], dest.adapter)
        libraries, notes = _write_libraries(items, dest, folder, formats)
        result = Conversion(items, dest, libraries, notes, time.perf_counter() - t0, workers.where)
        write_json_atomic(folder / "convert.json", summary(result).model_dump(mode="json"))
        write_index(folder / "index.html", result)
    return result


def _converted(item: Item, folder: Path) -> Converted:
    """A converted material for the writers; a textured one's maps copied to `textures/<slot>/`."""
    report = item.done.report
    here = folder / "materials" / item.slot
    files = tuple(f.name for f in report.files)
    if report.textures is None:
        return Converted(item.entry.name, item.model, dict(report.params), here, files=files)
    maps = {}
    for m in report.textures.maps:
        rel = Path("textures") / item.slot / m.file
        try:
            (folder / rel).parent.mkdir(parents=True, exist_ok=True)
            write_bytes_atomic(folder / rel, (here / m.file).read_bytes())
        except OSError as exc:
            raise ConfigError(f"cannot copy the map: {exc.strerror or exc}", file=str(folder / rel)) from None
        filt = next(iter(item.entry.material.textures.values())).filter
        maps[m.param] = Texture(file=rel.as_posix(), colorspace=m.colorspace, filter=filt)  # type: ignore[arg-type]
    return Converted(item.entry.name, item.model, dict(report.textures.values), here, maps, files)


def _write_libraries(items: list[Item], dest: Destination, folder: Path,
                     formats: Formats) -> tuple[list[Path], list[str]]:
    """The libraries the target's writers make of the converted materials, and what was left out, why."""
    ok = [i for i in items if i.done is not None and i.done.report is not None]
    models = {i.model for i in ok}
    writers = formats.writers_for(dest.adapter, models) or [NativeFiles(dest.adapter)]
    converted, libraries, notes = {}, [], []
    for i in ok:
        try:
            converted[i.slot] = _converted(i, folder)
        except RemapError as exc:  # its maps could not be gathered: the others are written all the same
            notes.append(f"{i.entry.name}: left out of the libraries: {exc}")
    for writer in writers:
        mine = [converted[i.slot] for i in ok if i.slot in converted and (not writer.models or i.model in writer.models)]
        if not mine:
            continue
        try:
            libraries += writer.write(folder, mine)
        except RemapError as exc:
            notes.append(f"{writer.name}: not written: {exc}")
    return libraries, notes


@dataclass
class NativeFiles:
    """The library of a target no writer knows (a renderer defined in YAML): each material's
    native files (its definition's `native:`), gathered under `native/<slot>/`, the slot being
    the material's name made safe and unique as in `materials/`."""

    adapter: str
    name: str = "native files"
    models: tuple[str, ...] = ()

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        """The folder `native/` (one library: a folder per material), when any material has one."""
        out = []
        for item in items:
            natives = [name for name in item.files if name not in IMAGES and Path(name).name == name]
            dest = folder / "native" / item.folder.name  # the material's slot: its name, made safe and unique
            try:
                dest.mkdir(parents=True, exist_ok=True)
                for name in natives:
                    out.append(write_bytes_atomic(dest / name, (item.folder / name).read_bytes()))
            except OSError as exc:
                raise ConfigError(f"cannot gather the native files: {exc.strerror or exc}", file=str(dest)) from None
        return [folder / "native"] if out else []


def _recorded(path: Path):
    """`_line`, each finished job also appended to ``path`` as one JSON line (done, of, title, status,
    error); the file is started empty."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("")
    except OSError as exc:
        raise ConfigError(f"cannot write the events file: {exc.strerror or exc}", field="--events") from None

    def line(done: Done, i: int, n: int) -> str:
        r = done.report
        event = {"done": i, "of": n, "title": done.task.title, "status": r.verdict if r else "failed",
                 "error": r.metrics.relative_rmse if r else None}
        with path.open("a", encoding="utf-8") as f:
            f.write(json.dumps(event) + "\n")
        return _line(done, i, n)

    return line


def _line(done: Done, i: int, n: int) -> str:
    if done.report is None:
        return f"[{i}/{n}] {done.task.title}: FAILED: {done.error}"
    r = done.report
    how = "" if r.job.lookup is None else " through a table" + (
        f", texel by texel ({r.textures.width} x {r.textures.height}; textured check "
        + ", ".join(f"{c.condition} {c.error:.1%}" for c in r.textures.checks) + ")" if r.textures else "")
    return (f"[{i}/{n}] {done.task.title} -> {r.target.model}{how}: {r.metrics.relative_rmse:.2%}, {r.renders} "
            f"renders, {r.seconds:.1f} s, {r.verdict}" + (" [resumed]" if done.resumed else "")
            + (f" (redone: {done.redone})" if done.redone else ""))


def summary(result: Conversion) -> ConvertSummary:
    """`convert.json`."""
    rows = []
    for i in result.items:
        rep = i.done.report if i.done is not None else None
        rows.append(MaterialRow(name=i.entry.name, file=i.entry.file, status=i.status, reason=i.reason,
                                verdict=rep.as_verdict().told if rep else "",
                                slot=i.slot if rep is not None else None, model=i.model or None, model_why=i.why,
                                relative_rmse=rep.metrics.relative_rmse if rep else None,
                                perceptual=rep.metrics.perceptual if rep else None,
                                renders=rep.renders if rep else None, seconds=rep.seconds if rep else None,
                                resumed=bool(i.done and i.done.resumed), notes=i.entry.notes,
                                textured=i.entry.textured, tried=[
                                    TriedModel(model=t.model, slot=t.done.task.slot, status=t.status,
                                               relative_rmse=t.done.report.metrics.relative_rmse if t.done.report
                                               else None, kept=t.done is i.done) for t in i.tried]))
    return ConvertSummary(target=result.destination.adapter, model=result.destination.model, materials=rows,
                          converted=sum(i.done is not None and i.done.report is not None for i in result.items),
                          failed=len(result.failed), libraries=[p.name for p in result.libraries],
                          library_notes=result.library_notes, seconds=result.seconds, ran_in=result.where)
