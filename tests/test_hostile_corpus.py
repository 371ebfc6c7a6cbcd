"""The hostile corpus (tests/hostile_corpus.py): some 500 command-line runs with broken design
files, measured files, loops and options. Every run ends cleanly: a clean result, or one line
and exit 2 (1 for a computation the formulas cannot give); never a traceback, an internal error,
a hang, a NaN in an output or a warning on standard error."""

from tests.hostile_corpus import run_corpus


def test_the_hostile_corpus_ends_cleanly(tmp_path, capsys):
    counts, examples, seconds = run_corpus(tmp_path)
    total = sum(counts.values())
    with capsys.disabled():
        print(f"\nhostile corpus: {total} runs, {dict(counts)}, {sum(seconds.values()):.0f} s, "
              f"slowest {max(seconds.values()):.1f} s")
    assert total >= 500
    failures = {k: v for k, v in examples.items() if k not in ("ok", "refused")}
    assert not failures, failures
    assert counts["refused"] > 400  # most of it is bad input, refused at the door
