"""The command's start-up collects young objects rarely, and its work runs at the usual thresholds
with start-up's objects frozen (``process.collector``); checked in child processes, since the
collector's settings belong to the whole process."""

import subprocess
import sys
import textwrap

PROGRAM = textwrap.dedent("""
    import gc, weakref
    from probecommit.process import collector

    gc.set_threshold(700, 10, 10)
    collector.defer_collection()
    collector.defer_collection()  # twice: still the first call's thresholds to restore
    print(gc.get_threshold())
    class Node: pass
    a, b = Node(), Node()
    a.other, b.other = b, a  # a cycle, unreachable once dropped: garbage of the start-up
    gone = weakref.ref(a)
    del a, b
    print(gone() is not None, gc.get_freeze_count() == 0)
    print(collector.startup_done(), gc.get_threshold(), gone() is None, gc.get_freeze_count() > 0)
    print(collector.startup_done())  # once only
    gc.disable()
    collector.defer_collection()  # a disabled collector is left alone
    print(gc.get_threshold(), collector.startup_done())
""")

COMMAND = textwrap.dedent("""
    import gc
    import probecommit.cli.app as app
    from probecommit.cli.common import progress_bar

    def work():
        print(gc.get_threshold(), gc.get_freeze_count() == 0)
        progress_bar("units")  # the work begins
        print(gc.get_threshold(), gc.get_freeze_count() > 0)

    app.app = work
    app.main()
""")


def child(program: str) -> list[str]:
    done = subprocess.run([sys.executable, "-c", program], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout.splitlines()


def test_start_up_defers_collection_and_the_work_restores_it_with_start_ups_objects_frozen():
    assert child(PROGRAM) == [
        "(50000, 10, 10)",
        "True True",  # the cycle outlives its last reference while collection is deferred
        "True (700, 10, 10) True True",  # freed, not frozen
        "False",
        "(700, 10, 10) False",
    ]


def test_the_command_starts_deferred_and_its_progress_bar_ends_the_start_up():
    assert child(COMMAND) == ["(50000, 10, 10) True", "(700, 10, 10) True"]
