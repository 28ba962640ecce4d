#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Checks every relative link in the project's Markdown files: the file it names exists and, when
the link has a #fragment, the target has a heading with that anchor (GitHub's slug rules:
lower case, punctuation other than '-' and '_' removed, spaces to '-', duplicates numbered -1,
-2, ...). External links (http, https, mailto) are not checked.

    python3 scripts/check-doc-links.py [ROOT]      (exit 1 and one line per broken link)
"""
import os
import re
import subprocess
import sys

LINK = re.compile(r'(?<!\!)\[[^\]]*\]\(([^)\s]+)(?:\s+"[^"]*")?\)|!\[[^\]]*\]\(([^)\s]+)\)')
HEADING = re.compile(r'^(#{1,6})\s+(.*?)\s*#*\s*$')


def slug(text):
    text = re.sub(r'<[^>]+>', '', text).strip().lower()
    text = re.sub(r'[^\w\- ]', '', text)  # keeps letters (any script), digits, '_', '-', ' '
    return text.replace(' ', '-')


def anchors(path, cache={}):
    if path not in cache:
        seen, found, fence = {}, set(), False
        for line in open(path, encoding='utf-8'):
            if line.lstrip().startswith('```'):
                fence = not fence
                continue
            m = None if fence else HEADING.match(line)
            if m:
                s = slug(m.group(2))
                n = seen.get(s, 0)
                seen[s] = n + 1
                found.add(s if n == 0 else f'{s}-{n}')
        cache[path] = found
    return cache[path]


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..'))
    files = subprocess.run(['git', '-C', root, 'ls-files', '--cached', '--others', '--exclude-standard', '*.md'],
                           capture_output=True, text=True, check=True).stdout.split()
    broken = 0
    for rel in files:
        path = os.path.join(root, rel)
        if not os.path.exists(path):
            continue
        fence = False
        for number, line in enumerate(open(path, encoding='utf-8'), 1):
            if line.lstrip().startswith('```'):
                fence = not fence
            if fence:
                continue
            for m in LINK.finditer(re.sub(r'`[^`]*`', '', line)):
                target = m.group(1) or m.group(2)
                if re.match(r'^[a-z]+:', target):
                    continue
                file_part, _, fragment = target.partition('#')
                dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
                if not os.path.exists(dest):
                    print(f'{rel}:{number}: {target}: no such file')
                    broken += 1
                elif fragment and dest.endswith('.md') and fragment not in anchors(dest):
                    print(f'{rel}:{number}: {target}: no heading with anchor #{fragment}')
                    broken += 1
    print(f'{len(files)} Markdown files, {broken} broken links', file=sys.stderr)
    return 1 if broken else 0


if __name__ == '__main__':
    sys.exit(main())
