#!/usr/bin/env python3
"""Tests of tools/docs/channel_graph.py and tools/docs/check_links.py.

  docs_tools_test.py SOURCE_DIR    (ctest docs_tools_tests)
"""

import contextlib
import io
import os
import shutil
import sys
import tempfile
import unittest

ROOT = os.path.abspath(sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tools", "docs"))

import channel_graph  # noqa: E402
import check_links  # noqa: E402


def by_name(processes):
    return {p["name"]: p for p in processes}


class ChannelGraphOfTheDemo(unittest.TestCase):
    """The shipped demo deployment, read as the processes read their configs."""

    @classmethod
    def setUpClass(cls):
        cls.p = by_name(channel_graph.read_deployment(ROOT, "config/deploy/demo.deploy"))

    def test_fused_slam_publishes_pose_ekf_from_odometry_scans_and_place_cells(self):
        f = self.p["fused-slam"]
        self.assertEqual(f["config"], "config/fused_slam.ini")
        self.assertIn("POSE_EKF", f["pub"])
        self.assertEqual(sorted(f["sub"]), ["LASER_SCAN", "ODOMETRY", "POSE_PLACE_CELLS"])

    def test_the_demo_variants_are_read_where_the_command_names_them(self):
        self.assertEqual(self.p["sim"]["config"], "config/deploy/demo/sim.ini")
        # demo/sim.ini drives by commands and publishes no panoramas
        self.assertEqual(self.p["sim"]["sub"], ["DRIVE_COMMAND"])
        self.assertNotIn("OMNI_PANORAMA", self.p["sim"]["pub"])
        self.assertIn("DRIVE_COMMAND", self.p["navigator"]["pub"])

    def test_flags_of_the_command_override_the_config(self):
        # placecells --mode localize publishes poses and takes no explore poses; the explore instance
        # (--mode explore, from a file:// log) the other way round
        self.assertIn("POSE_PLACE_CELLS", self.p["placecells"]["pub"])
        self.assertNotIn("POSE_GROUND_TRUTH", self.p["placecells"]["sub"])
        self.assertIn("POSE_LASER_SLAM", self.p["explore.placecells"]["sub"])
        self.assertNotIn("POSE_GROUND_TRUTH", self.p["explore.placecells"]["sub"])
        self.assertNotIn("POSE_PLACE_CELLS", self.p["explore.placecells"]["pub"])
        self.assertIn("reads", self.p["explore.placecells"]["note"])
        self.assertIn("not the bus", self.p["explore.placecells"]["note"])
        # the exploration drive: sim --drive grid writes a log (mode=w) and takes no commands
        self.assertEqual(self.p["explore.drive"]["sub"], [])
        self.assertIn("writes", self.p["explore.drive"]["note"])
        self.assertIn("no bus", self.p["explore.slam"]["note"])
        self.assertEqual(self.p["landmarks"]["pub"], ["LANDMARKS_SURF"])

    def test_regular_expressions_match_the_published_channels(self):
        text = channel_graph.render(list(self.p.values()), "config/deploy/demo.deploy")
        viewer_line = [l for l in text.splitlines() if l.strip().endswith("--> p_viewer")][0]
        for c in ("POSE_EKF", "POSE_RATSLAM", "LANDMARKS_SURF", "POSE_GROUND_TRUTH"):
            self.assertIn(c, viewer_line)
        self.assertEqual(viewer_line.count("POSE_GROUND_TRUTH"), 1)
        # nothing in the demo publishes HOME_SNAPSHOT or ROUTE: dotted
        self.assertIn("HOME_SNAPSHOT -.-> p_homing", text)
        self.assertIn("ROUTE -.-> p_navigator", text)
        self.assertTrue(text.startswith(channel_graph.BEGIN) and text.rstrip().endswith(channel_graph.END))


class ChannelGraphOfOtherDeployments(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()

    def tearDown(self):
        shutil.rmtree(self.dir)

    def write(self, name, text):
        path = os.path.join(self.dir, name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def deploy(self, *processes):
        body = "[deployment]\nname = t\n\n[defaults]\ngroup = g\n"
        for name, command in processes:
            body += f"\n[process {name}]\ncommand = {command}\n"
        return self.write("t.deploy", body)

    def test_shipped_configs_prefix_and_method(self):
        d = self.deploy(("sim", "${bin}/sim --channel-prefix R1_"),
                        ("lm", "${bin}/landmarks --method sift"))
        p = by_name(channel_graph.read_deployment(ROOT, d))
        # config/sim.ini drives its scripted route: no DRIVE_COMMAND; every channel prefixed
        self.assertEqual(p["sim"]["sub"], [])
        self.assertIn("R1_OMNI_FRAME", p["sim"]["pub"])
        self.assertEqual(p["lm"]["pub"], ["LANDMARKS_SIFT"])

    def test_an_unknown_channel_key_is_an_error_naming_file_and_line(self):
        with open(os.path.join(ROOT, "config", "dead_reckoning.ini")) as f:
            text = f.read()
        ini = self.write("dr.ini", text.replace("[channels]\n", "[channels]\nextra = EXTRA\n", 1))
        d = self.deploy(("dr", f"${{bin}}/dead-reckoning --config {ini}"))
        with self.assertRaises(channel_graph.Error) as e:
            channel_graph.read_deployment(ROOT, d)
        self.assertIn(f"{ini}:", str(e.exception))
        self.assertIn("[channels] extra", str(e.exception))

    def test_an_unknown_program_is_an_error(self):
        d = self.deploy(("x", "${bin}/teleporter"))
        with self.assertRaises(channel_graph.Error) as e:
            channel_graph.read_deployment(ROOT, d)
        self.assertIn("teleporter", str(e.exception))

    def test_check_fails_on_a_stale_block_and_write_fixes_it(self):
        block = channel_graph.render(channel_graph.read_deployment(ROOT, "config/deploy/demo.deploy"),
                                     "config/deploy/demo.deploy")
        readme = self.write("README.md", "# t\n\n" + block.replace("POSE_EKF", "POSE_OLD", 1) + "\nafter\n")
        args = ["config/deploy/demo.deploy", "--root", ROOT]
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            self.assertEqual(channel_graph.main(args + ["--check", readme]), 1)
            self.assertEqual(channel_graph.main(args + ["--write", readme]), 0)
            self.assertEqual(channel_graph.main(args + ["--check", readme]), 0)
        with open(readme) as f:
            self.assertEqual(f.read(), "# t\n\n" + block + "\nafter\n")
        nomarkers = self.write("plain.md", "# t\n")
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            self.assertEqual(channel_graph.main(args + ["--check", nomarkers]), 2)


class CheckLinks(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()
        os.makedirs(os.path.join(self.dir, "docs"))
        with open(os.path.join(self.dir, "docs", "page.md"), "w") as f:
            f.write("# A page\n\n## The `bench` command: fast!\n\ntext\n")

    def tearDown(self):
        shutil.rmtree(self.dir)

    def problems(self, text):
        path = os.path.join(self.dir, "README.md")
        with open(path, "w") as f:
            f.write(text)
        return check_links.check(path, self.dir, {})

    def test_good_links_pass(self):
        self.assertEqual(self.problems(
            "[p](docs/page.md) [h](docs/page.md#the-bench-command-fast) ![i](docs) [x](https://example.org/nope)\n"
            "[self](#top)\n\n# Top\n\n[ref]: docs/page.md\n"), [])

    def test_a_missing_file_and_a_missing_heading_are_reported_with_their_line(self):
        p = self.problems("ok\n[p](docs/nope.md)\n[h](docs/page.md#no-such-heading)\n")
        self.assertEqual(len(p), 2)
        self.assertTrue(p[0].startswith("README.md:2:") and "docs/nope.md" in p[0])
        self.assertTrue(p[1].startswith("README.md:3:") and "no-such-heading" in p[1])

    def test_links_in_code_are_not_links(self):
        self.assertEqual(self.problems("`[a](nope.md)`\n```\n[b](nope.md)\n```\n"), [])


if __name__ == "__main__":
    unittest.main(verbosity=2)
