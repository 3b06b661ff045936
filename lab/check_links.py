#!/usr/bin/env python3
"""Every relative Markdown link in README.md, docs/ and lab/ resolves to a file or folder in the checkout.

Run from anywhere: python3 lab/check_links.py. Prints each broken link as FILE:LINE: TARGET and exits 1 if any.
Links with a scheme (https:, mailto:) and same-page anchors (#...) are not checked; a link's own #anchor is dropped.
"""
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LINK = re.compile(r'!?\[[^\]]*\]\(([^)\s]+)(?:\s+"[^"]*")?\)')


def markdown_files():
    yield os.path.join(ROOT, 'README.md')
    for top in ('docs', 'lab'):
        for folder, _, names in os.walk(os.path.join(ROOT, top)):
            for name in names:
                if name.endswith('.md'):
                    yield os.path.join(folder, name)


def main():
    broken = 0
    for path in markdown_files():
        in_code = False
        with open(path, encoding='utf-8') as f:
            for number, line in enumerate(f, 1):
                if line.lstrip().startswith('```'):
                    in_code = not in_code
                if in_code:
                    continue
                for target in LINK.findall(line):
                    if re.match(r'^[a-zA-Z][a-zA-Z0-9+.-]*:', target) or target.startswith('#'):
                        continue
                    file_part = target.split('#', 1)[0]
                    if not file_part:
                        continue
                    resolved = os.path.normpath(os.path.join(os.path.dirname(path), file_part))
                    if not os.path.exists(resolved):
                        print(f'{os.path.relpath(path, ROOT)}:{number}: {target}')
                        broken += 1
    print(f'{broken} broken relative link(s)' if broken else 'all relative links resolve')
    return 1 if broken else 0


if __name__ == '__main__':
    sys.exit(main())
