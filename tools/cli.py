"""The ``sandmod`` command line."""

from __future__ import annotations

import contextlib
import importlib.util
import json
import os
import sys
import time
from pathlib import Path

import click

from sandmod import __version__
from sandmod.errors import Problem, ProblemsError, display_path, printable
from sandmod.formats.modspec import ARCHETYPES, MOD_NAME, NAME
from sandmod.formats.recording import WriteError
from sandmod.formats.userfiles import Refused, check_output, inside
from sandmod.formats.worldspec import MAX_FRAMES
from sandmod.jobs.play import keys as play_keys
from sandmod.tools.entry import EXIT_INTERRUPTED

EXIT_USER_ERROR = 2


class _Group(click.Group):
    """Prints each problem in the user's input on its own line and exits 2, without a traceback."""

    def invoke(self, ctx: click.Context):
        try:
            try:
                return super().invoke(ctx)
            except KeyboardInterrupt:
                _stop_compiling()
                raise
            finally:
                _finish_compiling()
        except ProblemsError as exc:
            for problem in exc.problems:
                click.echo(str(problem), err=True)
            ctx.exit(EXIT_USER_ERROR)
        except KeyboardInterrupt:  # Ctrl-C: what was being written is gone, and a shell's status says so
            click.echo("interrupted", err=True)
            ctx.exit(EXIT_INTERRUPTED)


def _finish_compiling() -> None:
    """Wait for the kernel's parts a command left compiling while it ran (see compile_kernels), if any."""
    warmup = sys.modules.get("sandmod.jobs.warmup")
    if warmup is not None:
        warmup.finish_later()


def _stop_compiling() -> None:
    warmup = sys.modules.get("sandmod.jobs.warmup")
    if warmup is not None:
        warmup.abandon_later()


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="sandmod")
def cli() -> None:
    """A falling-sand engine in which every element is data."""


def _counted(count: int, noun: str) -> str:
    """'1 world', '2 worlds': a count and its noun, plural unless the count is one."""
    return f"{count} {noun}" if count == 1 else f"{count} {noun}s"


def _mod_folders(mod_dirs) -> list[Path]:
    """./mods when there is one, then every --mods DIR (a world's own mods/ beside it comes first: see load_world)."""
    from sandmod.world.loading import mod_folders

    return mod_folders(mod_dirs)


def _say(message: str) -> None:
    """A line for people, on stderr (out of the way of output that may be piped)."""
    click.echo(message, err=True)


class ThreadCount(click.ParamType):
    """A number of threads (1 to 256), or auto (None): as many as pay."""

    name = "N|auto"

    def convert(self, value, param, ctx):
        if value is None or value == "auto":
            return None
        if isinstance(value, int):
            number = value
        else:
            try:
                number = int(value)
            except ValueError:
                self.fail(f"{value!r} is neither a number of threads nor auto", param, ctx)
        if not 1 <= number <= 256:
            self.fail(f"{number} is not in 1 to 256", param, ctx)
        return number


class MemorySize(click.ParamType):
    """A number of bytes like 4G or 512M, or none (None: no limit)."""

    name = "SIZE"

    def convert(self, value, param, ctx):
        if value is None or isinstance(value, int) or str(value).lower() == "none":
            return None if value is None or str(value).lower() == "none" else value
        from sandmod.formats.limits import parse_size

        try:
            return parse_size(str(value))
        except ValueError as exc:
            self.fail(str(exc), param, ctx)


def _images(result) -> str:
    """'41 images', or '41 images (2 distinct)' when most were like the one before."""
    text = _counted(result.images, "image")
    return text if result.distinct == result.images else f"{text} ({result.distinct} distinct)"


def _named(count: int | None) -> int | str:
    """A thread count as results show it: the number, or auto."""
    from sandmod.jobs.benchmark import AUTO

    return AUTO if count is None else count


_mods_option = click.option(
    "--mods",
    "mod_dirs",
    multiple=True,
    type=click.Path(file_okay=False, path_type=Path),
    help="Another folder of mods (repeatable).",
)


_max_memory_option = click.option(
    "--max-memory",
    type=MemorySize(),
    default="4G",
    show_default=True,
    help="Refuse, before it starts, a world or render that would take more memory than this (e.g. 16G; none: no limit).",
)


@cli.command()
@click.argument("world", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(path_type=Path), help="Output file, or folder for png-frames (default: WORLD.gif here).")
@click.option("--format", "format_name", help="Output format: gif, apng, webp, png-frames, or a plugin's (default: by the output's extension).")
@click.option("--frames", type=click.IntRange(1, MAX_FRAMES), help="Frames to simulate.")
@click.option("--every", type=click.IntRange(1, 1000), help="Frames simulated per image.")
@click.option("--seed", type=click.IntRange(0, 2**32 - 1), help="Seed (overrides the world's).")
@click.option("--scale", type=click.IntRange(1, 16), help="Pixels per cell (nearest neighbour).")
@click.option("--fps", type=click.FloatRange(0, 50, min_open=True), help="Images per second (GIF: delays of at least 20 ms).")
@click.option("--loop", type=click.IntRange(0, 65535), help="Times the animation plays; 0 = forever.")
@click.option("--crop", type=(int, int, int, int), metavar="X Y W H", help="Record only this region of cells.")
@click.option("--still", type=click.Path(dir_okay=False, path_type=Path), help="Also write the last image as a PNG.")
@click.option("--save-snapshot", type=click.Path(dir_okay=False, path_type=Path), help="Save the final state to an .npz file.")
@click.option("--from-snapshot", type=click.Path(dir_okay=False, path_type=Path), help="Start from a saved state (and its frame and seed).")
@click.option("--threads", type=ThreadCount(), help="Threads to step the world on, or auto (the default: as many as pay, see below); the frames are the same on any number.")
@_max_memory_option
@click.option("-q", "--quiet", is_flag=True, help="No progress bar or summary.")
@_mods_option
def render(world, output, format_name, frames, every, seed, scale, fps, loop, crop, still, save_snapshot, from_snapshot, threads, max_memory, quiet, mod_dirs) -> None:
    """Simulate WORLD (a world .toml file) and write an animation.

    \b
    Threads: a world too small for a second thread to pay steps on one; a
    larger one tries its thread counts as it runs and keeps the faster (on
    a busy machine, often one). Set OMP_WAIT_POLICY or NUMBA_THREADING_LAYER
    to change how numba's threads wait and which library runs them.
    """
    if threads is not None:
        _thread_pool(threads)
    from sandmod.world.loading import load_world
    from sandmod.formats.recording import output_bytes
    from sandmod.jobs.render import Framing, render_problems
    from sandmod.jobs.render import render as run
    from sandmod.world.snapshots import write_snapshot
    from sandmod.jobs.warmup import compile_new_kernels, compile_parallel

    loaded = load_world(world, mod_dirs=_mod_folders(mod_dirs), seed=seed, max_memory=max_memory)
    loaded.world.threads = threads
    warnings = [str(w) for w in loaded.warnings]
    if from_snapshot is not None:
        from sandmod.world.snapshots import load_snapshot

        warnings += [f"{display_path(from_snapshot)}: {w}" for w in load_snapshot(loaded.world, from_snapshot)]
        if seed is not None:
            loaded.world.seed = seed
    for warning in warnings:
        click.echo(printable(f"warning: {warning}"), err=True)
    settings = loaded.spec.render
    recorder, output = _recorder_and_output(loaded, world, output, format_name)
    _check_outputs([*loaded.inputs, from_snapshot], [(output, recorder.folder is not None), (still, False), (save_snapshot, False)])
    framing = Framing(scale or settings.scale, _crop(loaded, crop))
    frames, every = frames or settings.frames, every or settings.every
    refused = render_problems(recorder, loaded.world, framing, frames, every, loaded.memory)
    if refused:
        raise ProblemsError([Problem(display_path(output), None, "", message) for message in refused])
    compile_new_kernels(loaded.world.ruleset, announce=None if quiet else _say, first_frame_of=loaded.world)
    compile_parallel(loaded.world, announce=None if quiet else _say)
    started = time.perf_counter()
    options = dict(
        frames=frames,
        every=every,
        framing=framing,
        fps=fps or settings.fps,
        loop=settings.loop if loop is None else loop,
        still=still,
        also=[] if save_snapshot is None else [(save_snapshot, write_snapshot)],
    )
    with _writing(output):
        if quiet or not sys.stderr.isatty():
            result = run(loaded.world, recorder, output, **options)
        else:
            with click.progressbar(length=frames, label=f"{world.name}", file=sys.stderr) as bar:
                result = run(loaded.world, recorder, output, progress=bar.update, **options)
    if not quiet:
        extras = "".join(f", {what} {display_path(path)}" for what, path in (("still", still), ("snapshot", save_snapshot)) if path)
        click.echo(
            f"wrote {display_path(output)}: {_images(result)} of {result.width}x{result.height} "
            f"from {_counted(result.frames, 'frame')} in {time.perf_counter() - started:.1f} s ({output_bytes(output) / 1e6:.2f} MB){extras}"
        )


def _thread_pool(most: int) -> None:
    """Let this process step worlds on up to ``most`` threads: numba's pool is sized when numba is
    imported, so a larger one than the CPUs is asked for first; one sized already is a usage error."""
    import os

    from sandmod.jobs.benchmark import max_threads

    if most > max_threads() and "numba" not in sys.modules:
        os.environ["NUMBA_NUM_THREADS"] = str(most)  # read when numba is imported, just below
    import numba

    if most > numba.config.NUMBA_NUM_THREADS:  # numba was imported before us, with fewer
        raise click.BadParameter(f"at most {numba.config.NUMBA_NUM_THREADS} in this process", param_hint="'--threads'")


@contextlib.contextmanager
def _writing(path: Path):
    """Turn a failure to write ``path`` (a full disk, a folder in the way) into a problem naming it,
    or naming the output a WriteError names."""
    try:
        yield
    except OSError as exc:
        target = exc.target if isinstance(exc, WriteError) else path
        raise ProblemsError([Problem(display_path(target), None, "", f"cannot write: {exc.strerror or exc}")]) from None


def _recorder_and_output(loaded, world: Path, output: Path | None, format_name: str | None):
    """The recorder (by --format, the world's render.format, or the output's extension) and the output path."""
    settings, registry = loaded.spec.render, loaded.registry
    name = format_name or settings.format
    if name is not None:
        entry = registry.recorders.get(name)
        if entry is None:
            message = f"unknown format '{name}' (known: {registry.recorder_choices()})"
            if format_name is None:
                raise ProblemsError([loaded.source.problem(("render", "format"), message)])
            raise click.BadParameter(message, param_hint="'--format'")
        recorder = entry.value
    if output is None:
        if settings.output:
            try:
                output = inside(loaded.source.folder, settings.output, "output")
            except Refused as exc:
                raise ProblemsError([loaded.source.problem(("render", "output"), str(exc))]) from None
        elif name is not None:
            output = Path(f"{world.stem}{recorder.extensions[0]}" if recorder.extensions else f"{world.stem}_frames")
        else:
            output = Path(f"{world.stem}.gif")
    if name is None:
        recorder = registry.recorder_for(output)
        if recorder is None:
            message = f"no recorder writes '{output.suffix}' files (known: {registry.recorder_choices()}); or give --format"
            raise ProblemsError([Problem(display_path(output), None, "", message)])
    return recorder, output


def _check_outputs(inputs, outputs) -> None:
    """Each output (a path and whether it is a folder) may be written: not a device, link or FIFO,
    not the world file or another input of this render, and no two the same."""
    problems, seen = [], set()
    for path in inputs:
        if path is not None:
            seen.add(path.resolve())
    for path, folder in outputs:
        if path is None:
            continue
        real = path.resolve()
        try:
            check_output(path, folder=folder)
            if real in seen:
                raise Refused("is an input of this render or another of its outputs")
        except Refused as exc:
            problems.append(Problem(display_path(path), None, "", f"will not write here: {exc}"))
        seen.add(real)
    if problems:
        raise ProblemsError(problems)


def _crop(loaded, crop: tuple[int, int, int, int] | None):
    """The crop region from --crop or the world's render.crop, checked against the world."""
    from sandmod.jobs.render import Crop

    given = crop or loaded.spec.render.crop
    if given is None:
        return None
    region, world = Crop(*given), loaded.world
    if not region.fits(world.width, world.height):
        message = f"[x, y, width, height] = {list(region)} must lie inside the {world.width}x{world.height} world"
        if crop is None:
            raise ProblemsError([loaded.source.problem(("render", "crop"), message)])
        raise click.BadParameter(message, param_hint="'--crop'")
    return region


@cli.command("list")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
@click.option("--provenance", is_flag=True, help="Show which mod and file defined each element, and who overrode what.")
@_mods_option
def list_(as_json, provenance, mod_dirs) -> None:
    """List the elements and reactions of every mod found (the bundled ones, ./mods, --mods)."""
    from sandmod.world.loading import load_ruleset

    ruleset = load_ruleset(None, _mod_folders(mod_dirs))
    for warning in ruleset.warnings:
        click.echo(printable(f"warning: {warning}"), err=True)
    if provenance and not as_json:
        _provenance(ruleset)
        return
    plugin_of = {m.name: m.plugin for m in ruleset.mods}
    elements = [
        {
            "id": e.id,
            "mod": e.defined_by,
            "archetype": e.spec.archetype,
            "density": getattr(e.spec, "density", None),
            "tags": list(e.spec.tags),
            "description": e.spec.description,
            "plugin": plugin_of[e.defined_by],
            "file": e.source.name,
            "overrides": [
                {"mod": o.mod, "file": o.file, "line": o.line, "changes": {k: [a, b] for k, a, b in o.changes}} for o in e.history
            ],
        }
        for e in ruleset.by_id
    ]
    reactions = [
        {
            "mod": r.mod,
            "a": r.spec.a,
            "b": r.spec.b,
            "a_becomes": r.spec.a_becomes,
            "b_becomes": r.spec.b_becomes,
            "chance": r.spec.chance,
        }
        for r in ruleset.reactions
    ]
    if as_json:
        mods = [{"name": m.name, "version": m.spec.mod.version, "file": m.source.name, "plugin": m.plugin} for m in ruleset.mods]
        click.echo(json.dumps({"mods": mods, "elements": elements, "reactions": reactions}, indent=2))
        return
    rows = [(e["id"], e["archetype"], "" if e["density"] is None else f"{e['density']:g}", ", ".join(e["tags"]), e["description"]) for e in elements]
    _table(("ELEMENT", "ARCHETYPE", "DENSITY", "TAGS", "DESCRIPTION"), rows)
    click.echo()
    rows = [
        (f"{r['a']} + {r['b']}", f"{r['a_becomes'] or '(same)'} + {r['b_becomes'] or '(same)'}", f"{r['chance'] * 100:.3g}%", r["mod"])
        for r in reactions
    ]
    _table(("REACTION", "BECOMES", "CHANCE", "MOD"), rows)


def _provenance(ruleset) -> None:
    """Each element, the mod (and plugin) that defined it, and every override with what it changed."""
    plugin_of = {m.name: m.plugin for m in ruleset.mods}
    file_of = {m.name: m.source.name for m in ruleset.mods}
    for e in ruleset.by_id:
        origin = e.origin
        like = f", like {e.spec.like}" if e.spec.like else ""
        click.echo(printable(f"{e.id}: defined by {origin} ({file_of[origin]}, plugin {plugin_of[origin]}){like}"))
        for change in e.history:
            click.echo(printable(f"  {change.describe()}"))


def _table(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> None:
    rows = [tuple(printable(str(cell)) for cell in row) for row in rows]  # a mod's text cannot drive the terminal
    widths = [max(len(str(row[i])) for row in [header, *rows]) for i in range(len(header))]
    for row in [header, *rows]:
        click.echo("  ".join(str(cell).ljust(w) for cell, w in zip(row, widths)).rstrip())


@cli.command()
@click.argument("paths", nargs=-1, type=click.Path(path_type=Path))
@_max_memory_option
@_mods_option
def validate(paths, max_memory, mod_dirs) -> None:
    """Check mod files, world files and folders of either; exit 2 if anything is wrong.

    With no PATHS, checks every mod found (the bundled ones and ./mods).
    """
    from sandmod.jobs.checking import check
    from sandmod.world.loading import load_registry
    from sandmod.rules.modset import is_world
    from sandmod.formats.tomlsource import TomlSource

    from sandmod.rules.modset import is_sweep

    problems: list[Problem] = []
    folders, mod_files, worlds, sweeps = list(mod_dirs), [], [], []
    if not paths and Path("mods").is_dir():
        folders.append(Path("mods"))
    for path in paths:
        if path.is_dir():  # its mods, its world files as worlds, its sweeps as sweeps
            folders.append(path)
            worlds += _world_files(path)
            sweeps += _world_files(path, is_sweep)
            continue
        try:
            data = TomlSource.read(path).data
        except ProblemsError as exc:
            problems.extend(exc.problems)
            continue
        if is_world(data):
            worlds.append(path)
        elif is_sweep(data):
            sweeps.append(path)
        elif "mod" in data:
            mod_files.append(path)
        else:
            problems.append(Problem(display_path(path), 1, "", "neither a mod (no [mod] table) nor a world (no [world] table)"))
    report = check(load_registry(), folders, mod_files, worlds, _mod_folders(mod_dirs), max_memory)
    for sweep in sweeps:
        from sandmod.jobs.batch import read_sweep

        try:
            read_sweep(sweep, Path("."), _mod_folders(mod_dirs), max_memory=max_memory)
        except ProblemsError as exc:
            problems.extend(exc.problems)
    for warning in report.warnings:
        click.echo(printable(f"warning: {warning}"), err=True)
    if problems or report.problems:
        raise ProblemsError(problems + report.problems)
    click.echo(
        f"ok: {_counted(report.mods, 'mod')} ({_counted(report.elements, 'element')}, {_counted(report.reactions, 'reaction')}, "
        f"{_counted(report.tests, 'test')}), {_counted(report.worlds, 'world')}" + (f", {_counted(len(sweeps), 'sweep')}" if sweeps else "")
    )


def _world_files(folder: Path, kind=None) -> list[Path]:
    """The world files in a folder (or those ``kind`` says yes to; those that do not read are reported with its mods)."""
    from sandmod.rules.modset import is_world
    from sandmod.formats.tomlsource import TomlSource

    found = []
    for path in sorted(folder.glob("*.toml")):
        try:
            if (kind or is_world)(TomlSource.read(path).data):
                found.append(path)
        except ProblemsError:
            pass
    return found


def _write_new(path: Path, text: str, *, replace: bool = False) -> None:
    """Write ``text`` to ``path`` in one go; an existing file is an error unless ``replace``."""
    from sandmod.formats.recording import atomic_path

    if path.exists() and not replace:
        raise ProblemsError([Problem(display_path(path), None, "", "already exists; not overwriting it")])
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise ProblemsError([Problem(display_path(path), None, "", f"cannot write: {exc.strerror or exc}")]) from None
    click.echo(f"wrote {display_path(path)}")


def _name(pattern: str, what: str):
    import re

    def check(ctx, param, value: str) -> str:
        if not re.fullmatch(pattern, value):
            raise click.BadParameter(f"'{value}' is not a valid {what} (lower case letters, digits and _)")
        return value

    return check


def _like(ref: str | None, mod_dirs):
    """The spec of the element named by --like, from every mod found."""
    if ref is None:
        return None
    from sandmod.world.loading import load_ruleset

    ruleset = load_ruleset(None, _mod_folders(mod_dirs))
    try:
        return ruleset.elements[ruleset.index(ref)].spec
    except KeyError as exc:
        raise click.BadParameter(exc.args[0], param_hint="'--like'") from None


@cli.group()
def new() -> None:
    """Start a new mod or element from a commented, valid template."""


_ARCHETYPES = tuple(name for name in ARCHETYPES if name != "empty")  # what a new element may be


@new.command("mod")
@click.argument("name", callback=_name(MOD_NAME, "mod name"))
@click.option("--archetype", type=click.Choice(_ARCHETYPES), help="How its first element moves (default: powder, or --like's).")
@click.option("--like", help="Start the first element from an existing element's parameters.")
@click.option("--dir", "folder", type=click.Path(file_okay=False, path_type=Path), default=Path("mods"), show_default=True,
              help="The folder to write the new mod in.")
@_mods_option
def new_mod(name, archetype, like, folder, mod_dirs) -> None:
    """Write DIR/NAME.toml: a mod with one element called NAME (with _ for -) and a test of it."""
    from sandmod.jobs import scaffold

    spec = _like(like, mod_dirs)
    archetype = archetype or (spec.archetype if spec is not None else "powder")
    text = scaffold.new_mod(name, archetype, spec if spec is not None and spec.archetype == archetype else None)
    path = folder / f"{name}.toml"
    scaffold.check(text, display_path(path))
    _write_new(path, text)


@new.command("element")
@click.argument("name", callback=_name(NAME, "element name"))
@click.option("--archetype", type=click.Choice(_ARCHETYPES), help="How it moves (default: --like's, else powder).")
@click.option("--like", help="Start from an existing element's parameters (those its archetype accepts).")
@click.option("--mod", "mod_file", type=click.Path(dir_okay=False, path_type=Path), help="Add it to this mod file instead of a new mod.")
@click.option("--dir", "folder", type=click.Path(file_okay=False, path_type=Path), default=Path("mods"), show_default=True,
              help="The folder to write the new mod in.")
@_mods_option
def new_element(name, archetype, like, mod_file, folder, mod_dirs) -> None:
    """Write a new element NAME (with a test): into --mod FILE, or as a new mod DIR/NAME.toml."""
    from sandmod.jobs import scaffold
    from sandmod.formats.tomlsource import TomlSource

    spec = _like(like, mod_dirs)
    archetype = archetype or (spec.archetype if spec is not None else "powder")
    if mod_file is None:
        path = folder / f"{name}.toml"
        text = scaffold.new_mod(name, archetype, spec)
        scaffold.check(text, display_path(path))
        _write_new(path, text)
        return
    source = TomlSource.read(mod_file)
    if name in source.data.get("elements", {}):
        raise ProblemsError([source.problem(("elements", name), f"'{name}' is already in this mod")])
    _write_new(mod_file, scaffold.add_element(source.text, source.name, name, archetype, spec), replace=True)


@new.command("world")
@click.argument("name", callback=_name(r"[A-Za-z0-9_][A-Za-z0-9_.-]*", "file name"))
@click.option("--mod", "mods", multiple=True, help="A mod the world loads (repeatable; default: every mod found).")
@click.option("--pour", help="The element its emitter pours (default: a powder or liquid of your own mods, else sand).")
@click.option("--size", type=(click.IntRange(16, 4096), click.IntRange(16, 4096)), default=(160, 120), show_default=True,
              metavar="W H", help="Width and height of the world, in cells (16 to 4096).")
@_mods_option
def new_world(name, mods, pour, size, mod_dirs) -> None:
    """Write NAME.toml: a world with a floor and an emitter, recording the mods and versions it is made with."""
    path = Path(name if name.endswith(".toml") else f"{name}.toml")
    _write_new(path, _new_world_text(path, mods, pour, size, mod_dirs))


def _new_world_text(path: Path, mods, pour, size, mod_dirs) -> str:
    from sandmod.jobs import scaffold
    from sandmod.world.loading import load_registry
    from sandmod.rules.modset import find_mods
    from sandmod.rules.compiler import compile_mods

    modset = find_mods(load_registry(), _mod_folders(mod_dirs))
    unknown = [name for name in mods if name not in modset.mods]
    if unknown:
        found = ", ".join(sorted(modset.mods))
        raise click.BadParameter(f"no mod called {', '.join(map(repr, unknown))} was found (found: {found})", param_hint="'--mod'")
    ruleset = compile_mods(modset.select(list(mods) or None), modset.behaviours)
    if pour is None:  # a powder or liquid of the user's own mods (the one just written, say), else sand
        wanted = {m.name: m for m in ruleset.mods if not mods or m.name in mods}
        movers = [e for e in ruleset.elements if e.spec.archetype in ("powder", "liquid") and e.defined_by in wanted]
        own = [e for e in movers if wanted[e.defined_by].plugin == "user"]
        sand = [e for e in movers if e.id == "sand:sand"]
        pour = (own or sand or movers or [e for e in ruleset.elements if e.index])[0].id
    else:
        try:
            pour = ruleset.elements[ruleset.index(pour)].id
        except KeyError as exc:
            raise click.BadParameter(exc.args[0], param_hint="'--pour'") from None
    text = scaffold.new_world(size, list(mods) or None, {m.name: m.spec.mod.version for m in ruleset.mods}, pour)
    scaffold.check_world(text, display_path(path))
    return text


@new.command("sweep")
@click.argument("name", callback=_name(r"[A-Za-z0-9_][A-Za-z0-9_.-]*", "file name"))
@click.option("--world", "world", help="The world file it runs, relative to the sweep (default: world.toml, written too if it is not there).")
@_mods_option
def new_sweep(name, world, mod_dirs) -> None:
    """Write NAME.toml: a commented sweep for sandmod batch, over one world, seeds and sand's friction."""
    from sandmod.jobs import scaffold

    stem = name[:-5] if name.endswith(".toml") else name
    if world is not None and not Path(world).is_file():
        raise click.BadParameter(f"no world file {world!r} here (sandmod new world makes one)", param_hint="'--world'")
    if world is None:
        world = "world.toml"
        if not Path(world).exists():  # a sweep that runs as written needs a world: one pouring sand
            _write_new(Path(world), _new_world_text(Path(world), (), "sand", (160, 120), mod_dirs))
    _write_new(Path(f"{stem}.toml"), scaffold.new_sweep(stem, world))


@cli.command()
@click.argument("sweep_file", metavar="SWEEP.toml", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", "out", type=click.Path(file_okay=False, path_type=Path), help="Folder for the runs and the results (default: the sweep's name, here).")
@click.option("-j", "--jobs", type=click.IntRange(1, 256), help="Runs at a time: worker processes, or Dask workers (default: one per CPU).")
@click.option("--executor", type=click.Choice(["process", "dask"]), default="process", show_default=True,
              help="A pool of local processes, or Dask (the dask extra): a local cluster, or --scheduler's.")
@click.option("--scheduler", metavar="ADDRESS", help="With --executor dask: an existing cluster's scheduler, e.g. tcp://host:8786.")
@click.option("--resume", is_flag=True, help="Go on with the runs in the folder: those done are kept, the rest run.")
@click.option("--force", is_flag=True, help="Write into a folder that holds files sandmod batch did not write (they are left alone).")
@click.option("--dry-run", is_flag=True, help="List the runs and do none (with --resume: which are done).")
@click.option("--long", "long_table", is_flag=True, help="Also write results_long.csv: a row per run and metric.")
@_max_memory_option
@click.option("-q", "--quiet", is_flag=True, help="No progress or summary; failures and problems only.")
@_mods_option
def batch(sweep_file, out, jobs, executor, scheduler, resume, force, dry_run, long_table, max_memory, quiet, mod_dirs) -> None:
    """Run a sweep: every world x seed x combination of parameters, in parallel.

    Each run's files go into OUT/runs/ID/ (an animation, snapshots, its last
    frame, its row), and appear only when the run is complete; its log is
    OUT/logs/ID.log. OUT/results.csv (and results.parquet, with pyarrow) has
    a row per run, OUT/summary.csv each metric's mean and standard deviation
    across seeds, OUT/contact_sheet.png every run's last frame. The same run
    makes the same files on any executor and any number of workers. A run
    that fails has its error in its row and its log; the others go on (exit
    status 1). Ctrl-C or SIGTERM writes the table of the runs done and exits
    130 or 143: --resume goes on. At most 100,000 runs in one sweep.
    """
    from sandmod.jobs import batch as batching

    if scheduler is not None and executor != "dask":
        raise click.UsageError("--scheduler goes with --executor dask")
    if executor == "dask" and importlib.util.find_spec("distributed") is None:
        raise click.ClickException('the dask executor needs dask: pip install "sandmod[dask]"')
    out = (out or Path(sweep_file.stem)).absolute()  # as the workers see it, wherever they run
    workers = jobs or os.cpu_count() or 1
    sweep = batching.read_sweep(sweep_file, out, _mod_folders(mod_dirs), jobs=workers, max_memory=max_memory)
    folder = batching.OutputFolder(out)
    if dry_run:
        _dry_run(sweep.runs, folder if resume else None)
        return
    try:
        check_output(out, folder=True)
    except Refused as exc:
        raise ProblemsError([Problem(display_path(out), None, "", str(exc))]) from None
    with _writing(out):
        folder.claim(resume=resume, force=force)
    try:
        with _writing(out):
            _batch(sweep, folder, executor, workers, scheduler, long_table, quiet)
    finally:
        folder.clear_parts()
        folder.release()


def _dry_run(runs, folder) -> None:
    """List the runs; with a folder, say which of them are done there."""
    done = 0
    for run in runs:
        finished = folder is not None and folder.done_row(run, clear=False) is not None
        done += finished
        values = ", ".join(f"{k} = {v}" for k, v in run.parameters.items())
        click.echo(f"{run.id}  {run.world}  seed {run.seed}" + (f"  {values}" if values else "") + ("  (done)" if finished else ""))
    click.echo(_counted(len(runs), "run") + (f", {done} done" if folder is not None else ""))


def _batch(sweep, folder, executor: str, workers: int, scheduler: str | None, long_table: bool, quiet: bool) -> None:
    """Run what is not done, then write the tables and the contact sheet; on an interruption, the
    tables of the runs done, and exit 130 (Ctrl-C) or 143 (SIGTERM)."""
    from sandmod.jobs import batch as batching
    from sandmod.jobs.warmup import compile_kernels, compile_new_kernels

    runs = sweep.runs
    before = {run.id: row for run in runs if (row := folder.done_row(run)) is not None}
    todo = [run for run in runs if run.id not in before]
    if todo:  # compiled once, and loaded here, before the workers start (forked, they have it)
        compile_new_kernels(announce=None if quiet else _say)
        compile_kernels()
    started, fresh, interrupted = time.perf_counter(), {}, None
    try:
        for row in batching.run_all(todo, executor, workers, scheduler):
            fresh[row["id"]] = row
            if not quiet:
                _batch_progress(fresh, len(todo), started)
    except batching.Interrupted as stop:
        interrupted = stop.status
    folder.clear_parts()
    if interrupted:  # the workers may have finished more runs than reached this process
        fresh.update({run.id: row for run in todo if run.id not in fresh and (row := folder.done_row(run, clear=False))})
    rows = [row for run in runs if (row := fresh.get(run.id) or before.get(run.id)) is not None]
    written = batching.write_tables(rows, folder.path, long=long_table)
    failed = [row for row in fresh.values() if row["status"] != "done"]
    for row in failed:
        click.echo(f"failed: {row['id']} {row['world']} seed {row['seed']}: {row['error']} (log: {display_path(folder.path / 'logs' / (row['id'] + '.log'))})", err=True)
    if interrupted:
        _say(f"interrupted: {len(rows)} of {_counted(len(runs), 'run')} done, in {display_path(written[0])}; "
             f"the same command with --resume runs the rest")
        sys.exit(interrupted)
    sheet = batching.contact_sheet(rows, runs, folder.path)
    seconds = time.perf_counter() - started
    if not quiet:
        rate = f", {len(todo) / seconds * 60:.1f} runs a minute" if todo and seconds > 0 else ""
        names = ", ".join(display_path(p) for p in [*written, *([sheet] if sheet else [])])
        click.echo(f"{_counted(len(runs), 'run')} ({len(before)} done before), {len(failed)} failed, in {seconds:.1f} s{rate}: {names}")
    if failed:
        sys.exit(1)


def _batch_progress(fresh: dict, total: int, started: float) -> None:
    finished = len(fresh)
    failed = sum(row["status"] != "done" for row in fresh.values())
    left = (time.perf_counter() - started) / finished * (total - finished)
    line = f"batch: {finished} of {total} runs, {failed} failed, {left:.0f} s left"
    if sys.stderr.isatty():  # one line, redrawn
        click.echo(f"\r{line}   " + ("\n" if finished == total else ""), err=True, nl=False)
    else:
        _say(line)


@cli.command()
@click.argument("world", required=False, type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), default=Path("palette.png"), show_default=True)
@_mods_option
def palette(world, output, mod_dirs) -> None:
    """Write a PNG swatch card of every element's colours (of WORLD's mods, or of every mod found)."""
    from sandmod.formats.recording import atomic_path
    from sandmod.jobs.swatches import swatch_card

    if world is not None:
        from sandmod.world.loading import load_world

        ruleset = load_world(world, mod_dirs=_mod_folders(mod_dirs)).ruleset
    else:
        from sandmod.world.loading import load_ruleset

        ruleset = load_ruleset(None, _mod_folders(mod_dirs))
    with _writing(output), atomic_path(output) as tmp:
        swatch_card(ruleset).save(tmp, format="PNG")
    click.echo(f"wrote {display_path(output)}: {_counted(len(ruleset.elements), 'element')}")


@cli.command()
@click.option("--world", is_flag=True, help="The world file format instead of the mod format.")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), help="Write to this file (default: print it).")
def schema(world, output) -> None:
    """Print (or write) the JSON Schema of mod files, for editors' completion and checking.

    \b
    With Taplo / Even Better TOML, put this first line in a mod file:
      #:schema ./mod.schema.json
    """
    if world:
        from sandmod.formats.worldspec import WorldFile as model
    else:
        from sandmod.formats.modspec import ModFile as model
    document = {"$schema": "https://json-schema.org/draft/2020-12/schema", **model.model_json_schema()}
    document["title"] = "sandmod world file" if world else "sandmod mod file"
    text = json.dumps(document, indent=2) + "\n"
    if output is None:
        click.echo(text, nl=False)
    else:
        _write_new(output, text, replace=True)


@cli.command()
@click.option("-q", "--quiet", is_flag=True, help="Say nothing but errors.")
def warmup(quiet) -> None:
    """Compile the kernel now, so that later commands start at once.

    \b
    Every command compiles it when a new sandmod version first needs it;
    run this where waiting then would hurt: building a container image, a
    CI job's setup (keep the cache folder it names between jobs), before a
    class or a demo. It compiles the kernels for several threads too."""
    from sandmod.engine import kernelcache
    from sandmod.jobs.warmup import compile_kernels, compile_parallel

    say = (lambda line: None) if quiet else _say
    fresh = not kernelcache.is_compiled()
    if fresh:
        say(kernelcache.NOTICE)
    started = time.perf_counter()
    compile_kernels(announce=say, several_threads=True)
    fresh = compile_parallel(announce=say) or fresh  # loaded, if the line above compiled it
    done = "compiled" if fresh else "already compiled: loaded"
    say(f"{done} in {time.perf_counter() - started:.1f} s, kept in {display_path(kernelcache.kernel_cache_dir())}")


@cli.command("test")
@click.argument("mods", nargs=-1)
@_mods_option
def test_(mods, mod_dirs) -> None:
    """Run the interaction tests ([[tests]]) of the named mods, or of every mod found.

    Mods are looked for where 'sandmod validate' looks: the bundled ones,
    plugins' folders, ./mods and every --mods DIR. Exit status: 0 when every
    test passed, 1 when one failed, 2 when a file has a mistake.
    """
    from sandmod.world.loading import load_registry
    from sandmod.rules.modset import discover_mods
    from sandmod.jobs.modtests import TestRunner
    from sandmod.jobs.warmup import compile_new_kernels

    folders = _mod_folders(mod_dirs)
    modset, problems = discover_mods(load_registry(), folders)
    runner = TestRunner(modset)
    try:
        cases = runner.cases(mods or None)
    except ProblemsError as exc:
        raise ProblemsError(problems + exc.problems) from None
    if not cases:
        click.echo("no tests found" + (f" in mods {', '.join(mods)}" if mods else ""))
    else:
        compile_new_kernels(announce=_say)
    started, failed, errors = time.perf_counter(), 0, 0
    for case in cases:
        try:
            outcome = runner.run(case)
        except ProblemsError as exc:
            problems.extend(exc.problems)
            errors += 1
            click.echo(f"{case.id} ... ERROR (see below)")
            continue
        click.echo(f"{case.id} ... {'ok' if outcome.passed else 'FAILED'}")
        if not outcome.passed:
            failed += 1
            click.echo(outcome.report())
    if cases:
        passed = len(cases) - failed - errors
        click.echo(
            f"{passed} passed, {failed} failed" + (f", {errors} could not run" if errors else "")
            + f" in {time.perf_counter() - started:.1f} s"
        )
    if problems:
        raise ProblemsError(problems)
    if failed:
        sys.exit(1)


class WindowSize(click.ParamType):
    """A world's width and height, as WIDTHxHEIGHT (each 4 to 4096)."""

    name = "WxH"

    def convert(self, value, param, ctx):
        if isinstance(value, tuple):
            return value
        try:
            width, height = (int(part) for part in str(value).lower().split("x"))
        except ValueError:
            self.fail(f"{value!r} is not WIDTHxHEIGHT, e.g. 320x200", param, ctx)
        if not (4 <= width <= 4096 and 4 <= height <= 4096):
            self.fail(f"{value!r}: each side from 4 to 4096 cells", param, ctx)
        return width, height


@cli.command(epilog="\b\nIn the window:\n" + play_keys.help_text())
@click.argument("world", required=False, type=click.Path(dir_okay=False, path_type=Path))
@click.option("--size", type=WindowSize(), help="The size of a new, empty world, in cells.  [default: 320x200]")
@click.option("--scale", type=click.IntRange(1, 16), default=2, show_default=True, help="Pixels per cell.")
@click.option("--benchmark", "benchmark_frames", type=click.IntRange(1, 100000), metavar="FRAMES",
              help="Show this many frames headless as fast as they go, a step each, while a brush paints (a new world: over a busy scene of fire, heat and blasts); print frames a second and each phase's time.")
@click.option("--save-session", is_flag=True, help="Also write the session's world file when the window closes (s writes it at any time).")
@_mods_option
def play(world, size, scale, benchmark_frames, save_session, mod_dirs) -> None:
    """Play a world in a window: paint with the mouse, watch it fall, save the session as a world file.
    In the window, F1 (or ?) shows every key.

    Saving a mod file while playing reloads the mods within a second; a
    mistake in it is shown and the old rules go on.
    """
    if importlib.util.find_spec("pygame") is None:
        raise click.ClickException('sandmod play needs pygame-ce: pip install "sandmod[play]"')
    from sandmod.jobs import play as window
    from sandmod.jobs.session import Session
    from sandmod.jobs.warmup import compile_new_kernels, compile_parallel

    if world is not None and size is not None:
        raise click.UsageError("--size sizes a new world; a world file has its own size")
    session = Session.open(world, size=size or ((512, 384) if benchmark_frames and world is None else None), mod_dirs=_mod_folders(mod_dirs))
    compile_new_kernels(session.world.ruleset, announce=_say, first_frame_of=session.world)
    compile_parallel(session.world, announce=_say)  # before the window opens, not in its first frames
    if benchmark_frames:
        click.echo(json.dumps(window.benchmark(session, scale, benchmark_frames, busy=world is None)))
        return
    name = world.stem if world is not None else "play"
    folder = world.parent if world is not None else Path(".")
    session_path = folder / f"{name}-session.toml"
    shown = window.Play(session, scale=scale, session_path=session_path, save_on_exit=save_session)
    shown.run()
    if shown.not_saved:
        click.echo(shown.not_saved, err=True)
        sys.exit(1)
    if shown.saved_to is not None:
        click.echo(shown.saved_message)


@cli.command()
@click.option("--scene", "scenes", multiple=True,
              type=click.Choice(["mix", "halves", "everything", "settled", "patch"]), help="Scene to run (repeatable; default: mix).")
@click.option("--world", "worlds", multiple=True, type=click.Path(dir_okay=False, path_type=Path), metavar="WORLD.toml",
              help="A world file to time, as render starts it (repeatable).")
@click.option("--size", type=click.IntRange(256, 2048), help="The scenes' width and height in cells.  [default: 512]")
@click.option("--steps", type=click.IntRange(1, 100000), help="Steps to time.  [default: 1000; a world's own frames]")
@click.option("--threads", "thread_counts", multiple=True, type=ThreadCount(), help="Threads, or auto (repeatable; default: auto).")
@click.option("--pixels", is_flag=True, help="Time turning a frame into colour indices instead, compiled against numpy.")
@click.option("--memory", "memory_sizes", multiple=True, type=click.IntRange(64, 16384), metavar="SIZE",
              help="Measure the peak memory of rendering a SIZE x SIZE world (repeatable), against the estimate the memory limit checks.")
@click.option("--busy", type=click.IntRange(0, 256), default=0, help="Keep this many other processes busy on the CPUs while timing, as a user's machine is.")
@click.option("--no-sleep", is_flag=True, help="Update every chunk every step, as if none could sleep.")
@click.option("--seed", type=click.IntRange(0, 2**32 - 1), help="Seed.  [default: 0; a world's own]")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object per run.")
@click.option("--record", "formats", multiple=True, metavar="FORMAT",
              help="Time rendering instead: an image a step, recorded as FORMAT (repeatable: gif, apng, webp, png-frames).")
@_mods_option
def bench(scenes, worlds, size, steps, thread_counts, pixels, memory_sizes, busy, no_sleep, seed, as_json, formats, mod_dirs) -> None:
    """Time the kernel on a built-in scene or a world file: steps/s, million cell-updates/s, chunks awake, memory.

    \b
    Scenes (y = 0 is the top row; edges are closed):
      mix         a quarter sand, a quarter water, scattered by a fixed hash
      halves      the top half sand, the bottom half water
      everything  twelve elements: reactions, lifetimes, heat, fire, blasts
      settled     layers of sand and water at rest (compare with --no-sleep)
      patch       mix in a 512x512 stone box in the middle, the rest empty

    A --world runs as render runs it (its mods, scene, emitters, sprays and
    timeline), at its own size and seed, for its own number of frames
    unless --steps says otherwise; --mods adds mod folders for it.

    With --record, each step also makes an image and a recorder encodes it:
    prints images encoded a second and encoding's share of the render.
    --pixels times turning a frame (after up to 100 steps) into colour
    indices, the compiled way World.image does and the numpy way it did,
    in turns, on one thread.

    --memory SIZE renders a SIZE x SIZE world for a few frames in a fresh
    process and prints its peak memory beside the estimate that render's
    --max-memory is checked against.

    --busy N keeps N other processes spinning on the CPUs while it times,
    as on a user's machine.

    Developers' comparisons (another version of the kernel, thread counts
    in turns, the yardstick) are in tools/dev/bench.py in a checkout.
    """
    from sandmod.engine import kernelcache
    from sandmod.jobs import benchmark

    if memory_sizes:
        for side in memory_sizes:
            found = benchmark.render_peak_memory(side)
            _report(
                found,
                as_json,
                f"render {side}x{side}, {found.frames} frames to {found.format}: peak {found.peak_mb / 1024:.2f} GB "
                f"(estimated {found.estimate_mb / 1024:.2f} GB)",
            )
        return
    if size is not None and worlds and not scenes:
        raise click.UsageError("--size sizes the built-in scenes; a world file has its own size")
    thread_counts = thread_counts or (None,)
    _thread_pool(max((c for c in thread_counts if c is not None), default=1))
    from sandmod.world.loading import load_ruleset
    from sandmod.jobs.warmup import compile_kernels, compile_parallel

    benches = []
    for path in worlds:  # every file checked before anything is timed
        timed, warnings = benchmark.world_bench(path, mod_dirs=_mod_folders(mod_dirs), seed=seed)
        for warning in warnings:
            click.echo(printable(f"warning: {warning}"), err=True)
        benches.append(timed)
    ruleset = load_ruleset()
    if scenes or not worlds:
        benches[:0] = [benchmark.scene_bench(ruleset, scene, size or 512, seed or 0) for scene in scenes or ("mix",)]
    if not kernelcache.is_compiled():
        _say(kernelcache.NOTICE)
    compile_seconds = compile_kernels(ruleset, announce=_say if not kernelcache.is_compiled() else None)
    if any(count != 1 for count in thread_counts):
        compile_parallel(announce=_say)
    runs = [(b, steps or b.steps) for b in benches]
    if pixels:
        for b, count in runs:
            compiled, numpy = benchmark.time_pixels(b, min(count, 100))
            _report(
                benchmark.PixelsResult(b.name, b.width, b.height, round(compiled, 3), round(numpy, 3)),
                as_json,
                f"{b.name} {b.width}x{b.height}, a frame to pixels: {compiled:.3f} ms compiled, {numpy:.3f} ms in numpy ({numpy / compiled:.1f}x)",
            )
        return
    with benchmark.busy_processes(busy):
        _bench_runs(runs, thread_counts, as_json, formats, no_sleep, compile_seconds)


def _bench_runs(runs, thread_counts, as_json, formats, no_sleep, compile_seconds) -> None:
    from sandmod.jobs import benchmark

    if formats:
        _bench_recording(formats, runs, thread_counts, as_json)
    else:
        for b, count in runs:
            for threads in thread_counts:
                result = benchmark.run(b, count, threads, sleep=not no_sleep, compile_seconds=compile_seconds)
                _report(
                    result,
                    as_json,
                    f"{_what(b, count)}, {_threads(threads)}"
                    f"{', no sleeping' if no_sleep else ''}: {result.steps_per_second:.1f} steps/s, "
                    f"{result.mcell_updates_per_second:.1f} million cell-updates/s, {result.awake_fraction:.0%} of chunks awake, "
                    f"compile {result.compile_seconds:.1f} s, peak memory {result.peak_memory_mb:.0f} MB, "
                    f"state {result.state_bytes_per_cell:.2f} bytes/cell",
                )


def _what(bench, steps: int, unit: str = "steps") -> str:
    """A bench run's scene or world, its size and length, for people."""
    return f"{bench.name} {bench.width}x{bench.height}, {steps} {unit}"


def _threads(count: int | str | None) -> str:
    if count is None or count == "auto":
        return "auto threads"
    return f"{count} thread{'s' * (count > 1)}"


def _report(result, as_json: bool, line: str) -> None:
    """One bench run: its JSON object, or a line for people."""
    click.echo(json.dumps(result.as_dict()) if as_json else line)


def _bench_recording(formats, runs, thread_counts, as_json) -> None:
    import tempfile

    from sandmod.jobs import benchmark
    from sandmod.world.loading import load_registry

    registry = load_registry()
    unknown = [name for name in formats if name not in registry.recorders]
    if unknown:
        raise click.BadParameter(f"unknown format {unknown[0]!r} (known: {registry.recorder_choices()})", param_hint="'--record'")
    for b, steps in runs:
        for threads in thread_counts:
            for name in formats:
                with tempfile.TemporaryDirectory() as folder:
                    result = benchmark.record(b, registry.recorders[name].value, steps, threads, folder)
                _report(
                    result,
                    as_json,
                    f"{name} {_what(b, steps, 'images')}, {_threads(threads)}: "
                    f"encoding {result.images_per_second:.0f} images/s ({result.encode_share:.0%} of the render), "
                    f"images {steps / result.image_seconds:.0f}/s, steps {steps / result.step_seconds:.0f}/s, {result.file_mb:.2f} MB",
                )
