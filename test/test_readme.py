# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""
The README's commands, run: every shell and Python block works and prints what it shows.

The conventions the README follows (and this test holds):

- Fenced blocks marked ``bash``, ``console`` or ``python`` are run; other languages (``text``,
  ``yaml``, ``mermaid``, none) are not.
- The line just before an opening fence may be a tag: ``<!-- not run: REASON -->`` skips the
  block (the reason is required), ``<!-- run with planner_node running -->`` runs the block
  while ``.venv/bin/planner_node`` runs (started before it, ready, stopped by its PID after).
- The first two bash blocks are the two setup commands: never run, tagged ``not run``, and the
  second is exactly the command ``.ci/run`` runs.
- Every run block runs in one shared temporary directory, in README order (a file one block
  makes serves the next), with ``.venv/bin/`` meaning this Python's venv and the tests' ROS
  isolation (``ros_env``); the venv's bin is taken off PATH, as in a reader's fresh shell.
- bash: one ``bash -eo pipefail`` script that must exit 0. python: ``python -`` must exit 0.
- console: ``$ `` starts a command, continued on the next line while a line ends with a backslash;
  the other lines up to the next command are what it prints (stdout and stderr), line for line.
  ``...`` inside a line matches any text, a line of just ``...`` any number of lines; a
  command shown without output must print nothing. The block is one bash script (not -e).
- Each block has at most 120 s; the README has at most 250 lines.

``TRAJPLAN_README=path`` runs the test on another markdown file.
"""
from __future__ import annotations

from dataclasses import dataclass
import difflib
import os
from pathlib import Path
import re
import shlex
import signal
import subprocess
import sys
from typing import Mapping, Sequence
import uuid

import pytest
from trajplan_ros.tools.node_process import PlannerProcess, TIMEOUT_S

pytestmark = pytest.mark.system


REPO = Path(__file__).resolve().parents[1]
README = Path(os.environ.get('TRAJPLAN_README') or REPO / 'README.md')
CI_RUN = REPO / '.ci' / 'run'
MAX_README_LINES = 250
BLOCK_TIMEOUT_S = 120.0
RUN_LANGUAGES = ('bash', 'console', 'python')
WITH_NODE = '<!-- run with planner_node running -->'
NOT_RUN = re.compile(r'<!-- not run: (?P<reason>\S.*?) -->')
VENV_BIN = re.compile(r'(?<![\w./-])(?:\./)?\.venv/bin/')
FENCE = re.compile(r'^(?P<indent> {0,3})(?P<fence>`{3,}|~{3,})\s*(?P<language>[^`\s]*)')


# --- the markdown ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Block:
    """A fenced block: its fence's line (1-based), language, text and the tag just before."""

    line: int
    end: int
    language: str
    text: str
    tag: str = ''
    closed: bool = True

    @property
    def not_run(self) -> bool:
        return self.tag.startswith('<!-- not run')

    @property
    def with_node(self) -> bool:
        return self.tag == WITH_NODE


@dataclass(frozen=True)
class Command:
    """One ``$ `` command of a console block: its README line, text and expected output."""

    line: int
    text: str
    expected: tuple[str, ...]


def parse_blocks(markdown: str) -> list[Block]:
    """Return the fenced blocks in order (an unclosed fence runs to the end, as in CommonMark)."""
    lines = markdown.splitlines()
    blocks: list[Block] = []
    i = 0
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if not opening:
            i += 1
            continue
        fence, indent = opening['fence'], len(opening['indent'])
        closing = re.compile(rf'^ {{0,3}}{re.escape(fence[0])}{{{len(fence)},}}\s*$')
        j = i + 1
        while j < len(lines) and not closing.match(lines[j]):
            j += 1
        body = [re.sub(rf'^ {{0,{indent}}}', '', line) for line in lines[i + 1:j]]
        previous = lines[i - 1].strip() if i else ''
        blocks.append(Block(i + 1, j + 1, opening['language'].lower(),
                            ''.join(line + '\n' for line in body),
                            previous if previous.startswith('<!--') else '', j < len(lines)))
        i = j + 1
    return blocks


def setup_blocks(blocks: Sequence[Block]) -> list[Block]:
    """Return the two setup commands: the first two bash blocks."""
    return [b for b in blocks if b.language == 'bash'][:2]


def run_blocks(blocks: Sequence[Block]) -> list[Block]:
    """Return the blocks to run, in order: bash, console, python; not setup, not tagged."""
    setup = setup_blocks(blocks)
    return [b for b in blocks
            if b.language in RUN_LANGUAGES and not b.not_run and b not in setup]


def tag_problems(markdown: str) -> list[str]:
    """Return what is wrong with the tags: no reason, unknown, not before a fence, and so on."""
    blocks = parse_blocks(markdown)
    fences = {b.line for b in blocks}
    inside = {n for b in blocks for n in range(b.line, b.end + 1)}
    problems = [f'line {b.line}: unclosed {b.language} block' for b in blocks if not b.closed]
    problems += [f'line {b.line}: {WITH_NODE} on a {b.language or "plain"} block, which is not '
                 'run' for b in blocks if b.with_node and b.language not in RUN_LANGUAGES]
    for n, line in enumerate(markdown.splitlines(), start=1):
        tag = line.strip()
        if n in inside or not re.match(r'<!--\s*(not\s+)?run\b', tag):
            continue
        if re.match(r'<!--\s*not\s+run', tag) and not NOT_RUN.fullmatch(tag):
            problems.append(f'line {n}: {tag!r}: a not-run tag is `<!-- not run: REASON -->`')
        elif not re.match(r'<!--\s*not\s+run', tag) and tag != WITH_NODE:
            problems.append(f'line {n}: {tag!r}: unknown tag; the run tag is `{WITH_NODE}`')
        if n + 1 not in fences:
            problems.append(f'line {n}: {tag!r} is not on the line just before a fence')
    return problems


def parse_console(block: Block) -> list[Command]:
    """Split a console block into its commands, each with the lines it is shown to print."""
    parsed: list[tuple[int, list[str], list[str]]] = []
    continued = False
    for n, line in enumerate(block.text.splitlines(), start=block.line + 1):
        if continued or line.startswith('$ '):
            if continued:
                parsed[-1][1].append(line.rstrip())
            else:
                parsed.append((n, [line[2:].rstrip()], []))
            continued = line.rstrip().endswith('\\')
        elif parsed:
            parsed[-1][2].append(line.rstrip())
        else:
            raise ValueError(f'{where(block)}: line {n} is output before the first `$ ` command')
    commands = []
    for n, text, expected in parsed:
        while expected and not expected[-1]:
            expected.pop()
        commands.append(Command(n, '\n'.join(text), tuple(expected)))
    return commands


def lines_match(expected: Sequence[str], actual: Sequence[str]) -> bool:
    """Whether ``actual`` matches ``expected`` line for line (``...``: any text, or any lines)."""
    positions = {0}                    # how many actual lines the expected ones so far can cover
    for line in expected:
        if line.strip() == '...':
            positions = set(range(min(positions), len(actual) + 1)) if positions else set()
            continue
        regex = re.compile('.*'.join(map(re.escape, line.rstrip().split('...'))))
        positions = {i + 1 for i in positions
                     if i < len(actual) and regex.fullmatch(actual[i].rstrip())}
    return len(actual) in positions


# --- running a block ---------------------------------------------------------------------------

def where(block: Block) -> str:
    """Name a block as the test ids do: ``README.md:LINE``."""
    return f'{README.name}:{block.line}'


def venv_bin(text: str, quote: bool) -> str:
    """Replace ``.venv/bin/`` with this Python's venv's bin (shell-quoted if ``quote``)."""
    path = os.path.join(sys.prefix, 'bin', '')
    return VENV_BIN.sub(lambda _: shlex.quote(path) if quote else path, text)


def run(argv: Sequence[str], cwd: Path, env: Mapping[str, str],
        stdin: str | None = None) -> tuple[int | None, str]:
    """Run ``argv`` with stdout and stderr merged; the exit status (None: timed out), output."""
    proc = subprocess.Popen(argv, cwd=cwd, env=dict(env), text=True, errors='replace',
                            stdin=subprocess.DEVNULL if stdin is None else subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            start_new_session=True)
    try:
        out, _ = proc.communicate(stdin, timeout=BLOCK_TIMEOUT_S)
        return proc.returncode, out
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)      # the block's own process group, by its id
        out, _ = proc.communicate()
        return None, out
    except BaseException:
        os.killpg(proc.pid, signal.SIGKILL)
        raise


def console_script(commands: Sequence[Command], marker: str) -> str:
    """Return a bash script that prints ``marker STATUS`` around each command (keeping $?)."""
    lines = [f"printf '%s -\\n' {marker}"]
    for command in commands:
        lines += [venv_bin(command.text, quote=True),
                  f"__readme_status=$?; printf '%s %s\\n' {marker} \"$__readme_status\"; "
                  '(exit "$__readme_status")']
    return '\n'.join(lines) + '\n'


def console_mismatches(block: Block, commands: Sequence[Command], out: str,
                       marker: str) -> list[str]:
    """Compare each command's output (split at the markers) with what the README shows."""
    parts = re.split(rf'{marker} (-|\d+)\n', out)
    problems = [f'output before the first command:\n{parts[0]}'] if parts[0] else []
    for k, command in enumerate(commands):
        if 2 + 2 * k >= len(parts) - 1:
            problems.append(f'line {command.line}: $ {command.text}\nnever finished (the '
                            f'script ended before it); last output:\n{parts[-1]}')
            continue
        actual = parts[2 + 2 * k].splitlines()
        while actual and not actual[-1].strip():
            actual.pop()
        if not lines_match(command.expected, actual):
            diff = difflib.unified_diff(command.expected, actual, 'README', 'printed',
                                        lineterm='', n=2)
            problems.append(f'line {command.line}: $ {command.text}\n(exit status '
                            f'{parts[3 + 2 * k]}) printed:\n' + '\n'.join(actual)
                            + '\n--- difference:\n' + '\n'.join(list(diff)[2:]))
    return problems


def bash_script(block: Block) -> str:
    """Return a bash block as a script that names the README line of a command that fails."""
    offset = block.line - 1                         # the trap is line 1, the block's first is 2
    trap = f'trap \'echo "{README.name}:$((LINENO + {offset})): failed: $BASH_COMMAND" >&2\' ERR'
    return trap + '\n' + venv_bin(block.text, quote=True)


def run_block(block: Block, cwd: Path, env: Mapping[str, str]) -> str | None:
    """Run one block; what went wrong (naming the README line), or None."""
    python = os.path.join(sys.prefix, 'bin', 'python')
    if block.language == 'console':
        try:
            commands = parse_console(block)
        except ValueError as exc:
            return str(exc)
        marker = f'@@readme-{uuid.uuid4().hex}@@'
        status, out = run(['bash', '-c', console_script(commands, marker)], cwd, env)
        problems = console_mismatches(block, commands, out, marker) if status is not None else []
    elif block.language == 'bash':
        status, out = run(['bash', '-eo', 'pipefail', '-c', bash_script(block)], cwd, env)
        problems = [f'exit status {status}; output:\n{out}'] if status else []
    else:
        status, out = run([python, '-'], cwd, env, stdin=venv_bin(block.text, quote=False))
        problems = [f'exit status {status}; output:\n{out}'] if status else []
    if status is None:
        problems = [f'timed out after {BLOCK_TIMEOUT_S:.0f} s; output:\n{out}']
    if not problems:
        return None
    return f'{where(block)} ({block.language} block):\n' + '\n\n'.join(problems)


# --- fixtures -----------------------------------------------------------------------------------

BLOCKS = parse_blocks(README.read_text(encoding='utf-8'))


@pytest.fixture(scope='module')
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Give the one directory every block of the README runs in, in order."""
    return tmp_path_factory.mktemp('readme')


@pytest.fixture(scope='module')
def block_env(ros_env: dict[str, str]) -> dict[str, str]:
    """os.environ, the tests' DDS isolation, unbuffered Python, no venv on PATH."""
    env = dict(ros_env)
    env['PYTHONUNBUFFERED'] = '1'
    venv = os.path.realpath(os.path.join(sys.prefix, 'bin'))
    path = env.get('PATH', '').split(os.pathsep)
    env['PATH'] = os.pathsep.join(p for p in path if p and os.path.realpath(p) != venv)
    env.pop('VIRTUAL_ENV', None)
    return env


# --- the README ----------------------------------------------------------------------------------

@pytest.mark.parametrize('block', run_blocks(BLOCKS), ids=where)
def test_readme_block(block: Block, workdir: Path, block_env: dict[str, str]) -> None:
    if not block.with_node:
        problem = run_block(block, workdir, block_env)
        if problem:
            pytest.fail(problem, pytrace=False)
        return
    node = PlannerProcess(env=block_env)
    try:
        if node.wait_for(r'\]: ready: ', TIMEOUT_S) is None:
            pytest.fail(f'{where(block)}: planner_node ({" ".join(node.argv)}) not ready within '
                        f'{TIMEOUT_S:.0f} s; it said:\n' + '\n'.join(node.lines[-40:]),
                        pytrace=False)
        problem = run_block(block, workdir, block_env)
    finally:
        node.stop()
    if problem:
        pytest.fail(problem + '\n\nplanner_node said:\n' + '\n'.join(node.lines[-40:]),
                    pytrace=False)


def test_readme_is_short() -> None:
    lines = len(README.read_text(encoding='utf-8').splitlines())
    assert lines <= MAX_README_LINES, f'{README.name} has {lines} lines (at most 250)'


def test_readme_tags_are_well_formed() -> None:
    problems = tag_problems(README.read_text(encoding='utf-8'))
    assert not problems, f'{README.name}:\n' + '\n'.join(problems)


def test_setup_commands_are_not_run_and_the_second_is_what_ci_runs() -> None:
    setup = setup_blocks(BLOCKS)
    assert len(setup) == 2, f'{README.name}: expected two setup bash blocks, found {len(setup)}'
    for block in setup:
        assert block.not_run, f'{where(block)}: a setup command needs `<!-- not run: REASON -->`'
    ci = [line.strip() for line in CI_RUN.read_text(encoding='utf-8').splitlines()
          if re.match(r'python3 -m venv .*pytest', line.strip())]
    assert len(ci) == 1, f'{CI_RUN}: expected one `python3 -m venv ... pytest ...` line'
    shown = [line.strip() for line in setup[1].text.splitlines()
             if line.strip() and not line.strip().startswith('#')]
    assert shown == ci, f'{where(setup[1])}: the test command is not what .ci/run runs'


# --- the parser and the matcher ------------------------------------------------------------------

SAMPLE = """\
# Sample

<!-- not run: sets up -->
```bash
python3 -m venv .venv
```
<!-- not run: runs the tests -->
```bash
.venv/bin/python -m pytest
```
<!-- not run: needs a second terminal -->
```python
raise SystemExit(1)
```
<!-- run with planner_node running -->
```console
$ echo a \\
  b
a b
$ printf 'x\\ny\\nz\\n'
x
...
$ true
```

```text
$ not a command
```
"""


def test_parser_finds_blocks_tags_and_commands() -> None:
    blocks = parse_blocks(SAMPLE)
    assert [(b.line, b.language) for b in blocks] == [
        (4, 'bash'), (8, 'bash'), (12, 'python'), (16, 'console'), (26, 'text')]
    assert [b.line for b in run_blocks(blocks)] == [16]             # not run: x is skipped
    assert blocks[2].not_run and blocks[3].with_node
    commands = parse_console(blocks[3])
    assert [(c.line, c.text, c.expected) for c in commands] == [
        (17, 'echo a \\\n  b', ('a b',)), (20, "printf 'x\\ny\\nz\\n'", ('x', '...')),
        (23, 'true', ())]
    assert tag_problems(SAMPLE) == []


def test_tag_problems_are_reported() -> None:
    text = '<!-- not run: -->\n```bash\n```\n<!-- run later -->\n```console\n```\n' \
           '<!-- not run: far -->\n\n```bash\n```\n<!-- run with planner_node running -->\n' \
           '```text\n```\n'
    problems = tag_problems(text)
    assert [p.split(':')[0] for p in problems] == ['line 12', 'line 1', 'line 4', 'line 7']


@pytest.mark.parametrize('expected, actual, matches', [
    (['a', '...', 'd'], ['a', 'b', 'c', 'd'], True),
    (['a', '...', 'd'], ['a', 'd'], True),
    (['a', '...'], ['a'], True),
    (['...'], [], True),
    (['planned in ... ms'], ['planned in 9.3 ms'], True),
    (['planned in ... ms'], ['planned in 9.3 s'], False),
    (['(x) [1] .*'], ['(x) [1] .*  '], True),
    (['(x) [1] .*'], ['x 1 ab'], False),
    (['a b'], ['a c'], False),
    (['a'], ['a', 'b'], False),
    ([], ['anything'], False),
    ([], [], True),
])
def test_lines_match(expected: list[str], actual: list[str], matches: bool) -> None:
    assert lines_match(expected, actual) is matches


def test_a_console_block_is_compared_command_by_command(tmp_path: Path) -> None:
    block = Block(10, 16, 'console', "$ printf 'no newline'\nno newline\n$ false\n"
                  '$ echo "exit status $?"\nexit status 1\n$ echo one \\\n  two\none three\n')
    problem = run_block(block, tmp_path, os.environ)
    assert problem is not None and problem.startswith(f'{README.name}:10 (console block)')
    assert 'line 16: $ echo one' in problem and 'line 11' not in problem
    assert 'line 13' not in problem and 'line 14' not in problem
