#!/usr/bin/env python3
"""Checks that every doctest::Approx in tests/*.cpp states its scale.

doctest's Approx(v) passes when |a - v| < epsilon * (scale + max(|a|, |v|)) with scale 1
by default, so for quantities far below 1 (joules, metres, seconds of a millimetre sphere)
it passes almost anything. Rule: each `doctest::Approx(` must have `.scale(` before the
end of its statement (the next `;`); test::relative(v) (tests/test_support.hpp) is the
relative form, scale 0. `using doctest::Approx` is refused, since a bare Approx( would
escape the rule.

Usage: tools/check-approx.py [tests directory]
Prints each offending site (file:line). Exit 0 if none, 1 otherwise.
"""
import pathlib
import re
import sys

tests = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).parent.parent / "tests")
bad = 0
for path in sorted(tests.glob("*.cpp")):
    text = path.read_text()
    for m in re.finditer(r"using\s+doctest::Approx\b|\bdoctest::Approx\(", text):
        end = text.find(";", m.end())
        statement = text[m.start() : end if end >= 0 else len(text)]
        if m.group(0).startswith("using") or ".scale(" not in statement:
            line = text.count("\n", 0, m.start()) + 1
            print(f"{path}:{line}: doctest::Approx without .scale( (use test::relative or an explicit scale)")
            bad += 1
sys.exit(1 if bad else 0)
