#!/usr/bin/python3
"""toolchain/fuzz_findings.sh (make fuzz's verdict after each fuzzer) on artifact directories
written here, with a stand-in fuzzer whose answers are known.

    /usr/bin/python3 tests/integration/test_fuzz_findings.py   (ctest: fuzz_findings_script)
"""
import os
import subprocess
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "toolchain", "fuzz_findings.sh")

# A stand-in for a libFuzzer binary run on one input (FUZZER -timeout=7 FILE: the limit given):
# an input that says "slow" times out again (libFuzzer's timeout exit code, 70), any other runs
# in time.
FAKE_FUZZER = """#!/usr/bin/env bash
[[ "$1" == "-timeout=7" ]] || exit 3
if grep -q slow "$2"; then echo "ERROR: libFuzzer: timeout"; exit 70; fi
exit 0
"""


class FuzzFindings(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.fuzzer = os.path.join(self.tmp.name, "fuzz_fake")
        with open(self.fuzzer, "w") as f:
            f.write(FAKE_FUZZER)
        os.chmod(self.fuzzer, 0o755)
        self.dir = os.path.join(self.tmp.name, "work")
        os.makedirs(os.path.join(self.dir, "fuzz_fake"))  # the corpus copy beside the artifacts

    def tearDown(self):
        self.tmp.cleanup()

    def artifact(self, name, text="x"):
        with open(os.path.join(self.dir, name), "w") as f:
            f.write(text)

    def verdict(self):
        r = subprocess.run(["bash", SCRIPT, self.fuzzer, self.dir, "7"], capture_output=True,
                           text=True, check=False)
        return r.returncode, r.stdout

    def test_nothing_found_passes_silently(self):
        self.assertEqual(self.verdict(), (0, ""))

    def test_each_kind_of_crash_alone_is_a_finding(self):
        # The check this replaces listed crash-*, leak-* and timeout-* in one `ls`, which fails
        # unless every pattern matches: a crash alone passed.
        for name in ("crash-1", "leak-1", "oom-1"):
            with self.subTest(name=name):
                self.artifact(name)
                code, out = self.verdict()
                self.assertEqual(code, 1)
                self.assertIn(f"fuzz finding: {os.path.join(self.dir, name)}", out)
                os.remove(os.path.join(self.dir, name))

    def test_a_timeout_that_repeats_is_a_finding(self):
        self.artifact("timeout-1", "slow")
        code, out = self.verdict()
        self.assertEqual(code, 1)
        self.assertIn("timeout-1 times out again", out)
        self.assertIn("rerun-timeout-1.log", out)
        self.assertTrue(os.path.exists(os.path.join(self.dir, "timeout-1")))

    def test_a_timeout_that_does_not_repeat_was_the_machine(self):
        self.artifact("timeout-2", "fast")
        code, out = self.verdict()
        self.assertEqual(code, 0)
        self.assertIn("timeout-2 ran in time when run again", out)
        self.assertEqual(sorted(n for n in os.listdir(self.dir) if n != "fuzz_fake"),
                         ["rerun-timeout-2.log", "stalled-timeout-2"])
        # The next fuzzer's check sees nothing left.
        self.assertEqual(self.verdict(), (0, ""))

    def test_a_bad_call_is_a_usage_error(self):
        none = os.path.join(self.tmp.name, "none")
        for args in ([self.fuzzer, self.dir], [none, self.dir, "7"], [self.fuzzer, none, "7"],
                     [self.fuzzer, self.dir, "0"], [self.fuzzer, self.dir, "ten"]):
            r = subprocess.run(["bash", SCRIPT] + args, capture_output=True, text=True,
                               check=False)
            self.assertEqual(r.returncode, 2, args)
            self.assertIn("usage:", r.stderr)


if __name__ == "__main__":
    unittest.main()
