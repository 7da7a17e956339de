# The web panel in a real browser: tests/browser.py (CPython, Selenium, Debian's headless
# Chromium) run once, each of its tests a test here. Where the browser is missing (no apt to
# install it with), each skips, saying why. Its screenshot of the panel on a phone-sized
# screen goes to a scratch file, checked, then removed (the README's is examples/web_panel.png).
import os
import unittest

from shell import scratch, sh

SCREENSHOT = scratch("web_panel") + ".png"
TESTS = (
    "test_1_nothing_moves_when_the_page_loads_or_logs_in",
    "test_2_armed_a_slider_drag_moves_the_simulated_servo_there",
    "test_3_stop_mid_sequence_lets_every_joint_go_limp",
    "test_4_two_poses_recorded_play_back",
    "test_5_esc_is_the_stop_key",
    "test_6_closing_the_tab_mid_drag_stops_the_stream_within_the_dead_man_time",
    "test_7_a_lost_connection_stops_the_stream_within_the_dead_man_time",
    "test_8_one_button_says_stop_the_sequences_says_halt",
    "test_9_a_message_covers_no_button_and_goes_when_it_is_over",
    "test_10_a_wrong_password_is_said_in_words",
    "test_11_an_empty_time_adds_no_pose_in_0_ms",
    "test_12_what_capture_shows_is_what_is_added_and_a_step_is_edited_or_removed_alone",
    "test_13_the_browser_hears_no_refusal_before_the_login",
    "test_14_each_slider_shows_its_limits_its_target_and_where_the_joint_is",
    "test_15_a_pose_is_listed_in_the_joints_order",
    "test_16_the_arm_requests_answer_decides_not_a_poll_asked_before_it",
    "test_17_offline_the_page_says_at_once_it_has_no_contact_greyed_and_not_armed",
    "test_18_back_in_contact_the_page_says_the_dead_man_disarmed_it",
    "test_19_another_pages_stop_is_named_on_the_armed_page",
    "test_20_a_page_whose_login_other_logins_pushed_out_says_so",
    "test_21_without_an_arm_the_jog_section_says_why",
    "test_22_save_selects_the_name_saved_and_clear_and_load_ask_first",
    "test_23_halt_and_limp_say_on_the_page_what_they_do",
    "test_24_record_stop_and_play_back_and_no_teleop_says_why",
    "test_25_stop_with_the_board_stopped_says_so_in_2_5_s_and_when_it_lands",
    "test_26_limp_is_the_armed_pages_and_leaves_it_armed",
    "test_1_jog_moves_the_tool_point_a_step_and_refuses_what_it_cannot_reach",
    "test_2_stop_ends_a_jog_on_its_way",
    "test_3_ranges_done_before_a_joint_was_swept_is_refused_naming_it_once",
    "test_4_calibrated_by_hand_saved_and_homed_only_once_confirmed",
    "test_5_a_refusal_is_said_once_by_its_joint_and_goes_when_the_step_is_taken",
    "test_6_start_makes_every_joint_go_limp_so_it_asks_first",
    "test_1_after_a_jog_every_thumb_shows_its_target_and_a_key_goes_on_from_there",
    "test_2_after_a_jog_a_finger_on_the_thumb_goes_on_from_where_it_shows",
    "test_3_a_jogs_refusal_goes_when_a_jog_is_taken",
    "test_1_too_many_wrong_passwords_are_answered_in_words",
    "test_1_the_teleop_switch_drives_the_robot_from_the_leader_and_shows_its_rate",
)

_run = None


def browser():
    """(what browser.py printed, {test: verdict}), browser.py being run the first time."""
    global _run
    if _run is None:
        ok, out = sh(".venv/bin/python tests/browser.py " + SCREENSHOT)
        verdicts = {}
        for line in out.split("\n"):
            for name in TESTS:
                if line.startswith(name + " ") and " ... " in line:
                    verdicts[name] = line.rpartition(" ... ")[2].strip()
        _run = (out, verdicts)
    return _run


class Browser(unittest.TestCase):
    def check(self, name):
        out, verdicts = browser()
        if out.startswith("SKIP: "):  # (unittest 0.4's TestCase has no skipTest())
            raise unittest.SkipTest("NO BROWSER TEST: " + out.split("\n")[0][6:])
        self.assertEqual(verdicts.get(name), "ok", out)


def _test(name):
    return lambda self: self.check(name)


for _name in TESTS:
    setattr(Browser, _name, _test(_name))


class Screenshot(unittest.TestCase):
    def test_the_panel_was_photographed_on_a_phone_sized_screen(self):
        out, verdicts = browser()
        if out.startswith("SKIP: "):
            raise unittest.SkipTest("NO BROWSER TEST: " + out.split("\n")[0][6:])
        if verdicts.get(TESTS[1]) != "ok":  # the test that takes it
            self.fail("no screenshot: %s did not pass" % TESTS[1])
        with open(SCREENSHOT, "rb") as f:
            png = f.read()
        self.assertEqual(png[:8], b"\x89PNG\r\n\x1a\n")
        width = int.from_bytes(png[16:20], "big")
        height = int.from_bytes(png[20:24], "big")
        self.assertEqual((width, height), (780, 1688))  # 390 x 844 CSS pixels, at 2x
        os.remove(SCREENSHOT)
