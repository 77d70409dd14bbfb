#!/usr/bin/env python3
"""The judges of the deployment runs (tools/deploy/run_checks.py, tools/deploy/process_stats.py) on
run folders built here: each verdict passes on a good run and fails, naming the cause, when one thing
is wrong (a process that grew, a message lost, a subscriber short, cross-talk, a late sim, an
estimator's error growing, a channel stamped with the receiver's clock, a frame lost on the link).
The long ctests (two_host_*, robots_three_on_one_bus, soak_stack_2min) run these judges on real runs;
this test shows they can say FAIL. process_stats.py sample is run on a live process of known size.

usage: run_checks_test.py [unittest args]
"""
import csv
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import unittest

TOOLS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "deploy")
RUN_CHECKS = os.path.join(TOOLS, "run_checks.py")
PROCESS_STATS = os.path.join(TOOLS, "process_stats.py")
sys.path.insert(0, TOOLS)
import process_stats  # noqa: E402

DELIVERY_FIELDS = ["process", "runs", "reported_runs", "channel", "published", "received", "rejected",
                   "handler_errors", "recorded"]


def write_delivery(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=DELIVERY_FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({"runs": 1, "reported_runs": 1, "rejected": 0, "handler_errors": 0, **r})


def write_processes(path, growth_kb_by_process, duration_s=100, step_s=5):
    """Samples of every process: flat RSS, then growth_kb spread over the time after the first half."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["t_s", "process", "pid", "rss_kb", "cpu_s"])
        for i, (name, growth) in enumerate(sorted(growth_kb_by_process.items())):
            for t in range(0, duration_s + 1, step_s):
                extra = 0 if t <= duration_s / 2 else growth * (t - duration_s / 2) / (duration_s / 2)
                w.writerow([t, name, 1000 + i, int(50000 + extra), f"{0.1 * t:.2f}"])


def run_check(*args):
    p = subprocess.run([sys.executable, RUN_CHECKS, *args], capture_output=True, text=True)
    return p.returncode, p.stdout + p.stderr


class ProcessStatsTest(unittest.TestCase):
    def test_growth_counts_from_the_end_of_the_warm_up_and_cpu_over_restarts(self):
        rows = []
        # 'a' grows 40 MB during its warm-up (0-60 s), then 3 MB; 'b' restarts at 50 s (a new pid).
        for t in range(0, 121, 10):
            rows.append({"t_s": t, "process": "a", "pid": 1, "rss_kb": 10000 + min(t, 60) * 700 + max(0, t - 60) * 50,
                         "cpu_s": t * 0.5})
            pid, cpu = (2, t * 0.1) if t < 50 else (3, (t - 50) * 0.2)
            rows.append({"t_s": t, "process": "b", "pid": pid, "rss_kb": 5000, "cpu_s": cpu})
        s = process_stats.summarize(rows, warmup_s=60)
        self.assertEqual(s["a"]["rss_start_t_s"], 60)
        self.assertEqual(s["a"]["rss_growth_kb"], 60 * 50)
        self.assertEqual(s["a"]["rss_max_kb"], 10000 + 60 * 700 + 60 * 50)
        self.assertAlmostEqual(s["a"]["cpu_percent"], 50.0)
        self.assertEqual(s["b"]["pids"], 2)
        self.assertAlmostEqual(s["b"]["cpu_s"], 4.0 + 14.0)  # 0-40 s of the first pid, 50-120 s of the second
        j = process_stats.flat_json(s, max_growth_kb=2 * 1024)
        self.assertFalse(j["goal_flat_rss_met"])  # a grew 2.9 MB after the warm-up
        self.assertTrue(process_stats.flat_json(s, max_growth_kb=3 * 1024)["goal_flat_rss_met"])

    def test_sample_follows_a_live_process_and_summary_judges_its_growth(self):
        d = tempfile.mkdtemp(prefix="process_stats_test.")
        self.addCleanup(shutil.rmtree, d)
        # A process that holds 10 MB, then 40 MB more after 1.5 s, and ends at 3 s: os._exit, so no
        # sample can see the interpreter free its memory on the way out (under load it did).
        child = subprocess.Popen([sys.executable, "-c",
                                  "import os, time\na = bytearray(10 << 20)\ntime.sleep(1.5)\n"
                                  "b = bytearray(40 << 20)\ntime.sleep(1.5)\nos._exit(0)\n"])
        out = os.path.join(d, "p.csv")
        sampler = subprocess.run([sys.executable, PROCESS_STATS, "sample", "--out", out, "--pid", f"grower={child.pid}",
                                  "--interval-s", "0.2"], timeout=30)
        child.wait()
        self.assertEqual(sampler.returncode, 0)  # it stopped by itself when the process ended
        rows = process_stats.load_rows(out)
        self.assertGreater(len(rows), 8)
        self.assertTrue(all(r["process"] == "grower" and r["pid"] == child.pid for r in rows))
        s = process_stats.summarize(rows, warmup_s=0.6)
        self.assertGreater(s["grower"]["rss_growth_kb"], 35 * 1024)
        self.assertGreater(s["grower"]["rss_max_kb"], 50 * 1024)
        summary = [sys.executable, PROCESS_STATS, "summary", out, "--warmup-s", "0.6"]
        self.assertEqual(subprocess.run(summary + ["--max-rss-growth-mb", "20"], capture_output=True).returncode, 1)
        self.assertEqual(subprocess.run(summary + ["--max-rss-growth-mb", "60"], capture_output=True).returncode, 0)


class SoakCheckTest(unittest.TestCase):
    def make_run(self, growth_kb=None, lost=0, missed=0, restarts=0, ratslam_last=0.05):
        d = tempfile.mkdtemp(prefix="soak_check_test.")
        self.addCleanup(shutil.rmtree, d)
        write_processes(os.path.join(d, "processes.csv"), growth_kb or {"sim": 0, "placecells": 1000, "viewer": 3000})
        s = {"delivery_lost_total": lost, "delivery_missed_by_subscribers_total": missed, "delivery_exact_channels": 18,
             "process_restarts_total": restarts}
        for ch, first, last in (("pose_laser_slam", 0.005, 0.005), ("pose_ratslam", 0.05, ratslam_last),
                                ("pose_dead_reckoning", 0.2, 2.5)):
            s.update({f"{ch}_ate_window_first_m": first, f"{ch}_ate_window_last_m": last,
                      f"{ch}_ate_window_max_m": max(first, last), f"{ch}_ate_window_mean_m": (first + last) / 2,
                      f"{ch}_ate_trend_m_per_h": last - first, f"{ch}_ate_growth_m": last - first})
        with open(os.path.join(d, "summary.json"), "w") as f:
            json.dump(s, f)
        return d

    def soak(self, d):
        return run_check("soak", d, "--warmup-s", "20", "--max-rss-growth-mb", "20")

    def test_a_good_run_passes_with_dead_reckoning_growing(self):
        rc, out = self.soak(self.make_run())
        self.assertEqual(rc, 0, out)
        self.assertIn("# Soak: PASS", out)
        self.assertIn("grows by design", out)  # dead reckoning shown, not judged

    def test_a_process_growing_past_the_bound_fails_and_is_named(self):
        rc, out = self.soak(self.make_run(growth_kb={"sim": 0, "viewer": 25 * 1024}))
        self.assertEqual(rc, 1, out)
        self.assertIn("FAIL: RSS growth", out)
        self.assertIn("grew: viewer", out)

    def test_growth_before_the_end_of_the_warm_up_is_not_judged(self):
        # 25 MB, all of it before the warm-up ends (100 s of a 100 s run).
        d = self.make_run()
        write_processes(os.path.join(d, "processes.csv"), {"placecells": 25 * 1024})
        rc, out = run_check("soak", d, "--warmup-s", "100", "--max-rss-growth-mb", "20")
        self.assertEqual(rc, 0, out)

    def test_a_lost_message_a_missed_one_or_a_restart_fails(self):
        for kw, text in (({"lost": 1}, "FAIL: 1 messages lost"), ({"missed": 2}, "2 missed by a subscriber"),
                         ({"restarts": 1}, "FAIL: 1 process restarts")):
            rc, out = self.soak(self.make_run(**kw))
            self.assertEqual(rc, 1, (kw, out))
            self.assertIn(text, out)

    def test_an_estimator_whose_error_grows_fails_and_is_named(self):
        rc, out = self.soak(self.make_run(ratslam_last=0.30))  # +0.25 m, limit 0.5 * 0.175 + 0.02
        self.assertEqual(rc, 1, out)
        self.assertIn("growing: POSE_RATSLAM", out)

    def write_windows(self, d, per_channel, window_s=10):
        """log-report's ate_windows.csv: {channel: [RMSE of each window]}."""
        with open(os.path.join(d, "ate_windows.csv"), "w") as f:
            f.write("channel,window_start_s,window_end_s,poses,rmse_m\n")
            for ch, values in per_channel.items():
                for i, v in enumerate(values):
                    f.write(f"{ch},{i * window_s},{(i + 1) * window_s},100,{v}\n")

    def test_growth_is_judged_after_the_warm_up_from_the_windows(self):
        d = self.make_run()
        # Laser SLAM's error high during the warm-up (20 s), then flat: passes; RatSLAM flat, then rising.
        self.write_windows(d, {"POSE_LASER_SLAM": [0.2, 0.1, 0.005, 0.005, 0.005, 0.005, 0.005, 0.005, 0.005],
                               "POSE_RATSLAM": [0.05] * 5 + [0.2, 0.3, 0.4, 0.5]})
        rc, out = self.soak(d)
        self.assertEqual(rc, 1, out)
        self.assertIn("growing: POSE_RATSLAM", out)
        self.assertIn("POSE_LASER_SLAM: window RMSE", out)
        self.assertIn("growth after 20 s +0.000 m over 7 windows", out)
        with open(os.path.join(d, "soak.json")) as f:
            # after 20 s: 0.05, 0.05, 0.05, 0.2, 0.3, 0.4, 0.5; thirds of 2: (0.4 + 0.5) / 2 - 0.05
            self.assertAlmostEqual(json.load(f)["pose_ratslam_ate_growth_after_warmup_m"], 0.40, places=3)

    def test_an_estimator_with_a_longer_warm_up_than_the_run_is_shown_not_judged(self):
        d = self.make_run(ratslam_last=0.30)
        self.write_windows(d, {"POSE_LASER_SLAM": [0.005] * 9, "POSE_RATSLAM": [0.05, 0.1, 0.15, 0.2, 0.25, 0.3]})
        rc, out = run_check("soak", d, "--warmup-s", "20", "--estimator-warmup", "POSE_RATSLAM=600")
        self.assertEqual(rc, 0, out)
        self.assertIn("not judged: its warm-up of 600 s leaves 0 windows of this run", out)
        # The same run with RatSLAM's warm-up the run's: it grows.
        rc, out = self.soak(d)
        self.assertEqual(rc, 1, out)
        self.assertIn("growing: POSE_RATSLAM", out)


class RobotsCheckTest(unittest.TestCase):
    PREFIXES = ("R1_", "R2_")

    def make_run(self, received=None, extra_rows=(), late=None):
        """Two robots for 10 s: each sim's 100 frames, 100 scans, 500 odometry; its placecells and the
        logger have all of them unless `received` says otherwise ({(prefix, channel): count})."""
        received = received or {}
        d = tempfile.mkdtemp(prefix="robots_check_test.")
        self.addCleanup(shutil.rmtree, d)
        rows = []
        for p in self.PREFIXES:
            for ch, n in (("OMNI_FRAME", 100), ("LASER_SCAN", 100), ("ODOMETRY", 500)):
                rows.append({"process": f"{p}/sim", "channel": p + ch, "published": n, "received": 0, "recorded": n})
                rows.append({"process": f"{p}/placecells", "channel": p + ch, "published": 0,
                             "received": received.get((p, ch), n), "recorded": n})
            os.makedirs(os.path.join(d, "robots", p))
            with open(os.path.join(d, "robots", p, "sim.log"), "w") as f:
                f.write("sim: config sim.ini\n")
                wall = (late or {}).get(p, 10.0)
                f.write(f"sim: t=10.0 s  frames 100  scans 100  pose (1.00, 2.00, 3.00 deg)  distance 1.0 m  wall {wall:.2f} s\n")
        write_delivery(os.path.join(d, "delivery.csv"), rows + list(extra_rows))
        write_processes(os.path.join(d, "processes.csv"), {f"robot{i}.placecells": 0 for i in (1, 2)})
        return d

    def robots(self, d):
        return run_check("robots", d, "--prefixes", ",".join(self.PREFIXES), "--duration-s", "10")

    def test_a_good_run_passes(self):
        d = self.make_run()
        rc, out = self.robots(d)
        self.assertEqual(rc, 0, out)
        self.assertIn("# 2 robots on one bus: PASS", out)
        with open(os.path.join(d, "robots.json")) as f:
            j = json.load(f)
        self.assertTrue(j["robots_ok"])
        self.assertEqual(j["robots_short_processes"], [])
        self.assertEqual(j["robots_late_sims"], [])

    def test_cross_talk_fails_and_names_the_subscription(self):
        rc, out = self.robots(self.make_run(extra_rows=[{"process": "R2_/homing", "channel": "R1_OMNI_FRAME",
                                                         "published": 0, "received": 3, "recorded": 100}]))
        self.assertEqual(rc, 1, out)
        self.assertIn("FAIL: no cross-talk", out)
        self.assertIn("R2_/homing <- R1_OMNI_FRAME", out)

    def test_a_subscriber_short_of_one_frame_fails_and_is_named(self):
        d = self.make_run(received={("R2_", "OMNI_FRAME"): 99})
        rc, out = self.robots(d)
        self.assertEqual(rc, 1, out)
        self.assertIn("R2_/placecells R2_OMNI_FRAME 99/100", out)
        with open(os.path.join(d, "robots.json")) as f:
            self.assertEqual(json.load(f)["robots_short_processes"], ["R2_/placecells"])

    def test_a_restarted_subscriber_is_not_judged_short(self):
        rc, out = self.robots(self.make_run(extra_rows=[{"process": "R1_/homing", "runs": 2, "channel": "R1_OMNI_FRAME",
                                                         "published": 0, "received": 60, "recorded": 100}]))
        self.assertEqual(rc, 0, out)

    def test_a_message_missing_from_the_log_fails(self):
        d = self.make_run()
        with open(os.path.join(d, "delivery.csv")) as f:
            text = f.read()
        with open(os.path.join(d, "delivery.csv"), "w") as f:
            f.write(text.replace("R1_/sim,1,1,R1_LASER_SCAN,100,0,0,0,100", "R1_/sim,1,1,R1_LASER_SCAN,100,0,0,0,98"))
        rc, out = self.robots(d)
        self.assertEqual(rc, 1, out)
        self.assertIn("(log: R1_LASER_SCAN 98/100", out)

    def test_a_sim_behind_real_time_or_below_its_rates_fails(self):
        d = self.make_run(late={"R2_": 10.8})
        rc, out = self.robots(d)
        self.assertEqual(rc, 1, out)
        self.assertIn("late: R2_ 10 s at wall 10.8 s", out)
        rc, out = run_check("robots", self.make_run(), "--prefixes", "R1_,R2_", "--duration-s", "11")
        self.assertEqual(rc, 1, out)  # 100 frames are not 10 Hz for 11 s
        self.assertIn("FAIL: every sim published its frames and scans at 10 Hz", out)

    def test_the_pace_is_judged_at_the_sims_realtime_factor(self):
        d = self.make_run(late={"R1_": 20.2, "R2_": 19.9})  # 10 s of simulated time in about 20 s of wall time
        rc, out = run_check("robots", d, "--prefixes", "R1_,R2_", "--duration-s", "10", "--realtime-factor", "0.5")
        self.assertEqual(rc, 0, out)
        self.assertIn("PASS: every sim kept its pace (0.5 s of simulated time per wall second", out)
        rc, out = self.robots(d)  # at 1: 10 s late
        self.assertEqual(rc, 1, out)
        self.assertIn("late: R1_ 10 s at wall 20.2 s; R2_ 10 s at wall 19.9 s", out)
        d = self.make_run(late={"R1_": 22.0})  # at 0.5: 1 s of simulated time late
        rc, out = run_check("robots", d, "--prefixes", "R1_,R2_", "--duration-s", "10", "--realtime-factor", "0.5")
        self.assertEqual(rc, 1, out)
        self.assertIn("late: R1_ 10 s at wall 22 s", out)


def write_lcm_log(path, events):
    """An LCM log of (log_utime, channel, message_utime) events; each payload: an 8-byte hash, the utime."""
    with open(path, "wb") as f:
        for i, (log_utime, channel, utime) in enumerate(events):
            payload = struct.pack(">qq", 0x1234, utime) + b"\0" * 8
            ch = channel.encode()
            f.write(struct.pack(">IqqII", 0xEDA1DA01, i, log_utime, len(ch), len(payload)) + ch + payload)


class LinkCheckTest(unittest.TestCase):
    CHANNELS = ("OMNI_FRAME", "LASER_SCAN", "ODOMETRY", "POSE_GROUND_TRUTH", "DRIVE_COMMAND", "POSE_LASER_SLAM",
                "POSE_EKF")

    def make_run(self, clock_offset_s=2.0, stamped_by_receiver=(), lost_frame=False, slow_ms=1.0):
        d = tempfile.mkdtemp(prefix="link_check_test.")
        self.addCleanup(shutil.rmtree, d)
        os.makedirs(os.path.join(d, "processes"))
        t0 = 1_700_000_000_000_000
        for sent_csv, arrived_csv in (("link-idle-sent.csv", "link-idle-arrived.csv"),
                                      (os.path.join("processes", "sim-frame-times.csv"), "link-base.csv")):
            with open(os.path.join(d, sent_csv), "w") as s, open(os.path.join(d, arrived_csv), "w") as a:
                s.write("utime,publish_utime\n")
                a.write("utime,recv_utime\n")
                for k in range(20):
                    u = t0 + k * 100_000
                    s.write(f"{u},{u + 1000}\n")
                    if not (lost_frame and k == 7):
                        a.write(f"{u},{u + 1000 + int(slow_ms * 1000)}\n")
        rows = [{"process": "sim", "channel": ch, "published": 20, "received": 0, "recorded": 20}
                for ch in self.CHANNELS[:4]]
        rows += [{"process": "navigator", "channel": "DRIVE_COMMAND", "published": 20, "received": 0, "recorded": 20},
                 {"process": "sim", "channel": "DRIVE_COMMAND", "published": 0, "received": 20, "recorded": 20}]
        write_delivery(os.path.join(d, "delivery.csv"), rows)
        with open(os.path.join(d, "summary.json"), "w") as f:
            json.dump({"delivery_lost_total": 0, "delivery_missed_by_subscribers_total": 0,
                       "delivery_exact_channels": len(self.CHANNELS)}, f)
        # The base's recorder (its clock) logs each message 5 ms after its stamp; the robot's clock, and
        # so every stamp carried along, is clock_offset_s ahead, except where the receiver restamps.
        events = []
        for k in range(20):
            base_now = t0 + k * 100_000
            for ch in self.CHANNELS:
                stamp = base_now if ch in stamped_by_receiver else base_now + int(clock_offset_s * 1e6)
                events.append((base_now + 5000, ch, stamp))
        write_lcm_log(os.path.join(d, "run.lcmlog"), events)
        return d

    def link(self, d, offset="2"):
        return run_check("link", d, "--clock-offset-s", offset)

    def test_a_good_link_with_the_robot_clock_off_passes(self):
        d = self.make_run()
        rc, out = self.link(d)
        self.assertEqual(rc, 0, out)
        with open(os.path.join(d, "link.json")) as f:
            j = json.load(f)
        self.assertEqual(j["link_idle_frames_lost"], 0)
        self.assertAlmostEqual(j["link_idle_frame_latency_median_ms"], 1.0)
        self.assertAlmostEqual(j["clock_pose_ekf_log_minus_utime_s"], -1.995)

    def test_an_output_stamped_with_the_receivers_clock_fails_and_is_named(self):
        rc, out = self.link(self.make_run(stamped_by_receiver=("POSE_EKF",)))
        self.assertEqual(rc, 1, out)
        self.assertIn("not: POSE_EKF", out)
        rc, out = self.link(self.make_run(), offset="0")  # the stamps are 2 s off, the check told 0
        self.assertEqual(rc, 1, out)

    def test_a_frame_lost_on_the_link_or_a_slow_link_fails(self):
        rc, out = self.link(self.make_run(lost_frame=True))
        self.assertEqual(rc, 1, out)
        self.assertIn("reached the base: 19 of 20", out)
        rc, out = self.link(self.make_run(slow_ms=4.0))
        self.assertEqual(rc, 1, out)
        self.assertIn("FAIL: the link alone, raw 1 MB frames: from sim's publish to the base's receipt median 4.0 ms", out)


if __name__ == "__main__":
    unittest.main()
