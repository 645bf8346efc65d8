"""Print the worst values measured by the contact tests at the end of the session."""
from .helpers import WORST


def pytest_terminal_summary(terminalreporter):
    if not WORST:
        return
    tr = terminalreporter
    tr.section("contact: worst measured values")
    for key in sorted(WORST):
        tr.write_line(f"{key:<60s} {WORST[key]:.3e}")
