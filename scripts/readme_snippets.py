#!/usr/bin/env python3
"""Prints a README code block by name, so that the tests run the README's snippets as written.

A block is named by an HTML comment on the line before its opening fence: <!-- snippet: NAME -->.
Usage: readme_snippets.py NAME [README.md]; exits 1 if there is no such block."""
import re
import sys


def snippet(text, name):
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if re.fullmatch(rf"\s*<!--\s*snippet:\s*{re.escape(name)}\s*-->\s*", line):
            start = i + 1
            if start >= len(lines) or not lines[start].startswith("```"):
                sys.exit(f"snippet '{name}': no code block right after its marker")
            end = next((j for j in range(start + 1, len(lines)) if lines[j].startswith("```")), None)
            if end is None:
                sys.exit(f"snippet '{name}': unclosed code block")
            return "\n".join(lines[start + 1:end]) + "\n"
    sys.exit(f"snippet '{name}': not in the README")


if __name__ == "__main__":
    path = sys.argv[2] if len(sys.argv) > 2 else "README.md"
    sys.stdout.write(snippet(open(path, encoding="utf-8").read(), sys.argv[1]))
