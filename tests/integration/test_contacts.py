#!/usr/bin/python3
"""sim/eval/contacts.py on a companion-eval output written here, whose answers are known.

    /usr/bin/python3 tests/integration/test_contacts.py   (ctest: contacts_script)
"""
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "..", "..", "sim", "eval", "contacts.py")
sys.path.insert(0, os.path.dirname(SCRIPT))
import contacts  # noqa: E402

TRIALS = ("case,method,seed,scenario,success,failure\n"
          "random,objective,1,random-1,0,collision with a pedestrian at t=0.2 s\n"
          "random,fixed_behind,2,random-2,0,collision with the person at t=0.2 s\n"
          "random,fixed_side,3,random-3,1,\n"
          "random,pid,4,random-4,0,collision with a pedestrian at t=0.1 s\n"
          "random,pid,5,random-5,0,more than 2 m from the person for 5 s at t=9.0 s\n")
COLUMNS = ("t_s,robot_x_m,robot_y_m,person_x_m,person_y_m,nearest_pedestrian_x_m,"
           "nearest_pedestrian_y_m\n")


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)


def output_dir(root):
    """objective-1: the robot drives at 1 m/s along +x into a pedestrian standing at x = 0.8;
    fixed_behind-2: the robot stands and the person comes to 0.6 m; pid-4 has no samples."""
    write(os.path.join(root, "trials.csv"), TRIALS)
    rows = ["{:.1f},{:.1f},0,5,5,0.8,0\n".format(t, t) for t in (0.0, 0.1, 0.2, 0.3)]
    write(os.path.join(root, "samples", "random", "objective-1.csv"), COLUMNS + "".join(rows))
    rows = ["{:.1f},0,0,{:.1f},0,9,9\n".format(t, 0.8 - t) for t in (0.0, 0.1, 0.2)]
    write(os.path.join(root, "samples", "random", "fixed_behind-2.csv"), COLUMNS + "".join(rows))
    return root


class Contacts(unittest.TestCase):
    def test_the_robot_driving_in_and_someone_coming_to_it_are_told_apart(self):
        with tempfile.TemporaryDirectory() as d:
            found = {c["method"]: c for c in contacts.contacts(output_dir(d))}
        self.assertEqual(sorted(found), ["fixed_behind", "objective", "pid"])  # collisions only
        speed, toward, dist = found["objective"]["moved"]
        self.assertAlmostEqual(speed, 1.0, places=9)
        self.assertAlmostEqual(toward, 1.0, places=9)
        self.assertAlmostEqual(dist, 0.6, places=9)  # the last sample at or before 0.2 s
        self.assertEqual(found["objective"]["whom"], "a pedestrian")
        speed, toward, dist = found["fixed_behind"]["moved"]
        self.assertEqual((speed, toward), (0.0, 0.0))
        self.assertAlmostEqual(dist, 0.6, places=9)
        self.assertEqual(found["fixed_behind"]["whom"], "the person")
        self.assertIsNone(found["pid"]["moved"])

    def test_the_command_prints_a_row_each_and_the_count(self):
        with tempfile.TemporaryDirectory() as d:
            out = subprocess.run(["/usr/bin/python3", SCRIPT, output_dir(d)], check=True,
                                 capture_output=True, text=True).stdout
        self.assertIn("| random | objective | 1 | random-1 | a pedestrian | 0.2 | 1.00 | +1.00 | "
                      "0.60 | the robot drove into them |", out)
        self.assertIn("| random | fixed_behind | 2 | random-2 | the person | 0.2 | 0.00 | +0.00 | "
                      "0.60 | they came to the robot |", out)
        self.assertIn("| random | pid | 4 | random-4 | a pedestrian | 0.1 | - | - | - | "
                      "no samples (run with --samples) |", out)
        self.assertIn("3 contacts; the robot drove into them in 1.", out)

    def test_a_directory_that_is_not_an_output_is_an_error(self):
        with tempfile.TemporaryDirectory() as d:
            r = subprocess.run(["/usr/bin/python3", SCRIPT, d], capture_output=True, text=True)
            self.assertEqual(r.returncode, 2)
            self.assertIn("no trials.csv", r.stderr)
            write(os.path.join(d, "trials.csv"), "a,b\n1,2\n")
            r = subprocess.run(["/usr/bin/python3", SCRIPT, d], capture_output=True, text=True)
            self.assertEqual(r.returncode, 2)
            self.assertIn("not a companion-eval output", r.stderr)


if __name__ == "__main__":
    unittest.main()
