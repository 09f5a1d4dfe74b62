#!/usr/bin/python3
"""toolchain/check_doc_links.py on Markdown trees written here, whose broken links are known.

    /usr/bin/python3 tests/integration/test_check_doc_links.py   (ctest: check_doc_links_script)
"""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "toolchain", "check_doc_links.py")
sys.path.insert(0, os.path.dirname(SCRIPT))
import check_doc_links  # noqa: E402

README = """# Front door

See [the results](docs/RESULTS.md#how-small-e_θ-can-be-qds-heading) and
[a later
section](docs/RESULTS.md#tables-12x09) and [here](#front-door).
Broken: [gone](docs/GONE.md), [no heading](docs/RESULTS.md#no-such-heading),
[second table](docs/RESULTS.md#tables-12x09-1), [third](docs/RESULTS.md#tables-12x09-2).
A picture: ![plot](docs/plot.png). Outside: [web](https://example.com/x.md#nowhere).
Not links: `[code](nowhere.md)` and

```sh
echo "[fenced](nowhere.md)"
```
"""

RESULTS = """# Results

## How small `e_θ` can be: q^d's heading

## Tables, 1.2x0.9

## Tables, 1.2x0.9

Back to [the front door](../README.md#front-door) and [up](../README.md#up).
"""


class CheckDocLinks(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        root = self.tmp.name
        os.makedirs(os.path.join(root, "docs"))
        os.makedirs(os.path.join(root, "build-x"))
        files = {"README.md": README, "docs/RESULTS.md": RESULTS, "docs/plot.png": "",
                 "build-x/OUT.md": "[ignored](missing.md)\n"}
        for name, text in files.items():
            with open(os.path.join(root, name), "w", encoding="utf-8") as f:
                f.write(text)

    def tearDown(self):
        self.tmp.cleanup()

    def test_headings_get_githubs_ids(self):
        self.assertEqual(check_doc_links.slug("How small `e_θ` can be: q^d's heading"),
                         "how-small-e_θ-can-be-qds-heading")
        self.assertEqual(check_doc_links.slug("The [link](x.md) text, 3 m/s"),
                         "the-link-text-3-ms")
        self.assertEqual(check_doc_links.anchors(os.path.join(self.tmp.name, "docs/RESULTS.md")),
                         {"results", "how-small-e_θ-can-be-qds-heading", "tables-12x09",
                          "tables-12x09-1"})

    def test_reports_exactly_the_broken_links(self):
        found = [(os.path.relpath(p, self.tmp.name), line, target, why)
                 for p, line, target, why in check_doc_links.broken_links(self.tmp.name)]
        self.assertEqual(found, [
            ("README.md", 6, "docs/GONE.md", "no such file"),
            ("README.md", 6, "docs/RESULTS.md#no-such-heading", "no such heading"),
            ("README.md", 7, "docs/RESULTS.md#tables-12x09-2", "no such heading"),
            (os.path.join("docs", "RESULTS.md"), 9, "../README.md#up", "no such heading"),
        ])

    def test_command_line_exit_status(self):
        bad = subprocess.run([sys.executable, SCRIPT, self.tmp.name], capture_output=True,
                             text=True, check=False)
        self.assertEqual(bad.returncode, 1)
        self.assertIn("README.md:6: docs/GONE.md: no such file", bad.stdout)
        self.assertIn("4 broken link(s)", bad.stdout)
        with open(os.path.join(self.tmp.name, "README.md"), "w", encoding="utf-8") as f:
            f.write("# Up\n\n[results](docs/RESULTS.md#results)\n")
        with open(os.path.join(self.tmp.name, "docs/RESULTS.md"), "w", encoding="utf-8") as f:
            f.write("# Results\n\n[up](../README.md#up)\n")
        good = subprocess.run([sys.executable, SCRIPT, self.tmp.name], capture_output=True,
                              text=True, check=False)
        self.assertEqual((good.returncode, good.stdout), (0, ""))


if __name__ == "__main__":
    unittest.main()
