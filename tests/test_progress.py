"""One progress display: silent in library calls, one rich bar at a time in the long commands."""

from __future__ import annotations

from grip_env.progress import progress_bar, shown


def test_a_bar_shows_only_inside_shown_and_never_nested(capsys):
    with progress_bar(3, "outside") as bar:
        bar.advance()
    assert "outside" not in capsys.readouterr().err
    with shown(), progress_bar(2, "outer") as bar:
        with progress_bar(5, "inner") as inner:
            inner.advance(5)
        bar.advance(2, info="2 done")
    err = capsys.readouterr().err
    assert "outer" in err and "2/2" in err and "2 done" in err
    assert "inner" not in err


def test_enabled_overrides_shown(capsys):
    with progress_bar(1, "forced", enabled=True) as bar:
        bar.advance()
    with shown(), progress_bar(1, "muted", enabled=False) as bar:
        bar.advance()
    err = capsys.readouterr().err
    assert "forced" in err and "muted" not in err


def test_train_shows_the_cross_validation_bar(generated_dataset_dir, tmp_path):
    from cli_runs import cli

    code, output = cli("train", "--data", generated_dataset_dir, "--out", tmp_path / "m",
                       "--models", "logreg")
    assert code == 0, output
    assert "cross-validation" in output


def test_into_a_file_a_plain_line_is_written_now_and_then(capsys, monkeypatch):
    from grip_env import progress

    monkeypatch.setattr(progress, "LOG_SECONDS", 0.0)
    with shown(), progress_bar(2, "logged") as bar:
        bar.advance(info="first")
    err = capsys.readouterr().err
    assert "logged: 1/2 first" in err
