#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Docs that run: executes every shell block (```sh) of the Markdown files given, in order within
each file, against the build being tested, and checks each command's exit code.

    run_doc_blocks.py --source SRC --build BUILD [--shared DATA] [--slow] FILE...
    run_doc_blocks.py --source SRC --build BUILD --covers FILE

How the docs are written, and what the test makes of it:

- Commands are written as a user types them at the repository root: `build/pipeline/lidarcal ...`,
  data as `data/...` and the shared recordings as `../shared/data/...`. Each file runs in a fresh
  temporary directory that links every top-level entry of SRC, with `build` linking BUILD and
  `../shared/data` linking DATA, so the commands run unchanged.
- Scratch outputs are written under /tmp/ (`-o /tmp/model.json`); the test maps /tmp/ to a
  directory of its own, so runs never meet each other or the user's files.
- The blocks of one file run in order, each in its own bash (`set -e -o pipefail`), so a block may
  read what the blocks before it wrote. Every command must exit 0, except one whose comment says
  `# exits N`: it must exit N.
- A ```text block shows what the last ```sh block above it (no heading between) prints: each of
  its lines must appear in that block's output (stdout and stderr), in that order, runs of spaces
  counting as one; a line `...` stands for lines left out.
- A block that reads ../shared/data is skipped, with a message, when that folder is absent.
- A block that cannot run in a test (it installs the machine, needs a robot or a ROS 2 machine)
  carries on the line above it a marker that Markdown does not show, with the reason the test
  prints:  <!-- docs-test: skip: REASON -->
- A block that takes long (a minute or more) carries  <!-- docs-test: slow -->  instead: it runs
  only with --slow (CI's step for the tests labelled slow), which runs only such blocks, so each
  must stand alone.

--covers FILE checks that the shell blocks of FILE (skipped ones included) run every command that
`lidarcal --help` lists, and no command it does not list.

Exit code 0 when every block ran as written, 1 otherwise.
"""
import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time

FENCE = re.compile(r'^\s*```\s*([\w-]*)')
MARKER = re.compile(r'^\s*<!--\s*docs-test:\s*skip:\s*(.*?)\s*-->\s*$')
SLOW = re.compile(r'^\s*<!--\s*docs-test:\s*slow\s*-->\s*$')
EXITS = re.compile(r'#.*\bexits (\d+)\b')
TMP = re.compile(r'(?<![\w./-])/tmp/')
COMMAND = re.compile(r'(?<![\w/.-])(?:build/pipeline/)?lidarcal(?:\s+-q)?\s+([a-z][a-z0-9-]*)')


class Block:
    def __init__(self, line, text, skip, slow):
        self.line = line      # line number of the opening fence (1-based)
        self.text = text      # the shell commands
        self.skip = skip      # reason given by a marker, or None
        self.slow = slow      # marked slow: runs only with --slow
        self.expected = None  # lines of the ```text blocks that show its output, or None


def parse_blocks(path):
    """The ```sh blocks of a Markdown file, with their markers and output blocks."""
    lines = open(path, encoding='utf-8').read().split('\n')
    blocks, i, last_sh_end = [], 0, None
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            if lines[i].startswith('#'):
                last_sh_end = None
            i += 1
            continue
        lang, start = m.group(1), i
        i += 1
        body = []
        while i < len(lines) and not FENCE.match(lines[i]):
            body.append(lines[i])
            i += 1
        i += 1  # the closing fence
        if lang == 'sh':
            k = start - 1
            while k >= 0 and not lines[k].strip():
                k -= 1
            marker = MARKER.match(lines[k]) if k >= 0 else None
            slow = bool(SLOW.match(lines[k])) if k >= 0 else False
            blocks.append(Block(start + 1, '\n'.join(body), marker.group(1) if marker else None,
                                slow))
            last_sh_end = len(blocks) - 1
            continue
        if lang == 'text' and last_sh_end is not None:
            blocks[last_sh_end].expected = (blocks[last_sh_end].expected or []) + ['...'] + body
    return blocks


def with_exit_checks(text):
    """The block's script: a command commented `# exits N` must exit N (continued lines count)."""
    out, group = [], []
    for line in text.split('\n'):
        group.append(line)
        if line.rstrip().endswith('\\'):
            continue
        m = EXITS.search(line)
        if m:
            what = shlex.quote(group[0].strip()[:120])
            out += ['__docs_rc=0', '{'] + group + ['} || __docs_rc=$?',
                    'if [ "$__docs_rc" != %s ]; then echo "docs-test: expected exit %s, got '
                    '$__docs_rc: "%s >&2; exit 1; fi' % (m.group(1), m.group(1), what)]
        else:
            out += group
        group = []
    return '\n'.join(out + group)


def squeeze(line):
    return ' '.join(line.split())


def missing_output(expected, output):
    """The first expected line not found in `output` after the ones before it, or None."""
    lines = [squeeze(line) for line in output.split('\n')]
    at = 0
    for want in expected:
        want = squeeze(want)
        if not want or want == '...':
            continue
        while at < len(lines) and want not in lines[at]:
            at += 1
        if at == len(lines):
            return want
        at += 1
    return None


def workspace(source, build, shared):
    """A temporary directory: repo/ (links to SRC's entries, build -> BUILD), shared/data, tmp/.
    Outputs written relative to repo/ stay there: the links are to inputs only."""
    root = tempfile.mkdtemp(prefix='lidarcal-docs-')
    repo = os.path.join(root, 'repo')
    os.mkdir(repo)
    for name in os.listdir(source):
        # Not the build trees, nor what `run` writes by default: the docs write there.
        if not name.startswith(('.', 'build', 'lidarcal-out')):
            os.symlink(os.path.join(source, name), os.path.join(repo, name))
    os.symlink(build, os.path.join(repo, 'build'))
    if shared and os.path.isdir(shared):
        os.mkdir(os.path.join(root, 'shared'))
        os.symlink(os.path.abspath(shared), os.path.join(root, 'shared', 'data'))
    os.mkdir(os.path.join(root, 'tmp'))
    return root


def run_block(block, where, root, timeout):
    """Runs one block; returns an error message or None."""
    scratch = os.path.join(root, 'tmp') + '/'
    script = ('set -eE -o pipefail\n'
              'trap \'echo "docs-test: exit $? from: $BASH_COMMAND" >&2\' ERR\n' +
              with_exit_checks(TMP.sub(scratch, block.text)) + '\n')
    started = time.monotonic()
    try:
        done = subprocess.run(['bash', '-c', script], cwd=os.path.join(root, 'repo'),
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout,
                              stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return 'did not finish within %d s' % timeout
    output = done.stdout.decode('utf-8', 'replace')
    seconds = time.monotonic() - started
    error = None
    if done.returncode != 0:
        error = 'exit code %d' % done.returncode
    elif block.expected is not None:
        lost = missing_output(block.expected, output)
        if lost is not None:
            error = 'its output lacks the line the doc shows: ' + lost
    if error:
        tail = '\n'.join(output.rstrip().split('\n')[-40:])
        return '%s\n--- the block:\n%s\n--- its output (last 40 lines):\n%s' % (
            error, block.text, tail)
    print('%s: ran in %.1f s' % (where, seconds))
    return None


def run_file(path, args):
    blocks = parse_blocks(path)
    root = workspace(os.path.abspath(args.source), os.path.abspath(args.build), args.shared)
    shared_here = os.path.isdir(os.path.join(root, 'shared', 'data'))
    failures = 0
    try:
        for block in blocks:
            where = '%s:%d' % (os.path.relpath(path, args.source), block.line)
            if block.skip is not None:
                print('%s: skipped: %s' % (where, block.skip))
                continue
            if block.slow != args.slow:
                if block.slow:
                    print('%s: marked slow: runs with --slow (the docs test labelled slow)' % where)
                continue
            if '../shared/data' in block.text and not shared_here:
                print('%s: skipped: it reads ../shared/data, which is absent (%s)' %
                      (where, args.shared))
                continue
            error = run_block(block, where, root, args.timeout)
            if error:
                print('%s: FAILED: %s' % (where, error))
                failures += 1
    finally:
        shutil.rmtree(root, ignore_errors=True)
    return failures


def listed_commands(build):
    """The commands `lidarcal --help` lists."""
    help_text = subprocess.run([os.path.join(build, 'pipeline', 'lidarcal'), '--help'],
                               stdout=subprocess.PIPE, check=True).stdout.decode()
    commands, inside = [], False
    for line in help_text.split('\n'):
        if line.startswith('Subcommands:'):
            inside = True
        elif inside and not line.strip():
            break
        elif inside and re.match(r'^  \S', line):
            commands.append(line.split()[0])
    return commands


def check_coverage(path, args):
    listed = listed_commands(args.build)
    text = '\n'.join(b.text for b in parse_blocks(path)).replace('\\\n', ' ')
    shown = set(COMMAND.findall(text))
    failures = 0
    for c in listed:
        if c not in shown:
            print('%s: no shell block runs `lidarcal %s`, which lidarcal --help lists' % (path, c))
            failures += 1
    for c in sorted(shown - set(listed)):
        print('%s: a shell block runs `lidarcal %s`, which lidarcal --help does not list' %
              (path, c))
        failures += 1
    if not failures:
        print('%s shows all %d commands of lidarcal --help' % (path, len(listed)))
    return failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--source', required=True, help='the source tree the docs describe')
    parser.add_argument('--build', required=True, help='the build to run the commands with')
    parser.add_argument('--shared', default='', help='the shared recordings (../shared/data)')
    parser.add_argument('--timeout', type=int, default=600, help='seconds per block')
    parser.add_argument('--slow', action='store_true',
                        help='run only the blocks marked <!-- docs-test: slow -->')
    parser.add_argument('--covers', help='check this file against lidarcal --help instead')
    parser.add_argument('files', nargs='*', help='Markdown files, relative to --source')
    args = parser.parse_args()
    if args.covers:
        return 1 if check_coverage(os.path.join(args.source, args.covers), args) else 0
    failures = sum(run_file(os.path.join(args.source, f), args) for f in args.files)
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
