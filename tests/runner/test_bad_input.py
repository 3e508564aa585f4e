"""Bad input, tried systematically (hypothesis).

The config loader, the probe-table reader and the audit's episode reader get random
malformed input. Each must answer with one clear line naming the field, column or
row (its own error type, never a traceback from deep inside NumPy or pandas), or
accept the input and read exactly the numbers it was given.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel

from probecommit.runner.config import ConfigError, StudyConfig, dump_config, load_config, parse_config
from probecommit.runner.study import preflight
from probecommit.store.probes import ProbeTableError, read_probes, validate_probes

SETTINGS = dict(deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def field_annotations(model: type[BaseModel] = StudyConfig, prefix: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    for name, f in model.model_fields.items():
        ann = f.annotation
        out[prefix + name] = ann
        if isinstance(ann, type) and issubclass(ann, BaseModel):
            out.update(field_annotations(ann, f"{prefix}{name}."))
    return out


ANNOTATIONS = field_annotations()
FIELDS = list(ANNOTATIONS)

#: Cross-field checks may name the other end of the pair.
RELATED = {
    "model.prior_low": ["model.prior_high", "instances.truth_low", "instances.truth_high"],
    "model.prior_high": ["model.prior_low", "instances.truth_low", "instances.truth_high"],
    "instances.truth_low": ["instances.truth_high"],
    "instances.truth_high": ["instances.truth_low"],
    "probes.budget": ["probes.schedule", "probes.budgets"],
    "belief.mixture_low": ["belief.mixture_high"],
    "model": ["instances"],
}

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(10**20), max_value=10**20),
    st.integers(min_value=-3, max_value=70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-20, max_value=20),
    st.sampled_from(["", "random", "mujoco", "analytic", "pybullet", "lhs", "uniform", "deployed", "corrected",
                     "mixture", "tempered", "probe_robust", "blind_bayes", "1e-3", "0.5", "3", "nan", "inf", "-1",
                     "yes", "no", "ok.", "..", "a\nb", "x: 1"]),
    st.text(max_size=12),
)
numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.floats(min_value=-60, max_value=60),
    st.integers(-60, 60), st.booleans(), st.sampled_from(["0.9", "nan", "-inf", "x"]),
)
values = st.one_of(
    st.recursive(
        scalars,
        lambda inner: st.one_of(st.lists(inner, max_size=10), st.dictionaries(st.text(max_size=8), inner, max_size=3)),
        max_leaves=12,
    ),
    # Near-valid: short numeric lists (boxes, budgets, schedules) with a bad element or two.
    st.lists(numbers, min_size=1, max_size=4),
    st.lists(st.integers(-2, 70), min_size=0, max_size=9),
)


def near_valid(path: str):
    """Values close to the field's type: where a loader is most tempted to guess."""
    text = str(ANNOTATIONS[path])
    if "tuple[float, float]" in text:
        # Mostly plausible boxes with a bad coordinate now and then.
        coord = st.one_of(st.floats(-12, 12), st.floats(0.0, 2.0),
                          st.sampled_from([math.nan, math.inf, -math.inf, True, "0.9", "nan", None]))
        return st.one_of(st.lists(coord, min_size=2, max_size=2), st.lists(numbers, min_size=0, max_size=3))
    if "list[int]" in text:
        return st.lists(st.one_of(st.integers(-2, 70), numbers), min_size=0, max_size=9)
    if "list[float]" in text:
        return st.one_of(st.just("random"), st.lists(numbers, min_size=0, max_size=12))
    if "Literal" in text or "list[" in text:
        words = st.sampled_from(["probe_robust", "blind_bayes", "blind_robust", "uniform", "lhs", "deployed",
                                 "corrected", "gaussian", "tempered", "mixture", "insertion", "Probe_Robust", " lhs"])
        return st.one_of(words, st.lists(words, max_size=4))
    if ANNOTATIONS[path] in (int, float, bool):
        return numbers
    return scalars


def nest(path: str, value) -> dict:
    data: dict = value
    for part in reversed(path.split(".")):
        data = {part: data}
    return data


def numbers_in(value):
    """The numbers a value spells, or None if it is not purely numeric."""
    if isinstance(value, bool) or value is None:
        return None
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, str):
        try:
            return [float(value)]
        except ValueError:
            return None
    if isinstance(value, (list, tuple)):
        parts = [numbers_in(v) for v in value]
        return None if any(p is None for p in parts) else [x for p in parts for x in p]
    return None


def parsed_value(config: StudyConfig, path: str):
    obj = config
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


def check_config_outcome(data: dict, path: str) -> None:
    try:
        config = parse_config(data)
    except ConfigError as exc:
        message = str(exc)
        assert "\n" not in message and message.strip() == message, repr(message)
        names = [path] + RELATED.get(path, []) + RELATED.get(path.split(".")[0], [])
        assert any(message.startswith(f"invalid config field '{n}") for n in names), (path, message)
        return
    # Accepted: it must really be usable, round-trip exactly, and mean the numbers given.
    assert isinstance(config, StudyConfig)
    instances = preflight(config) if config.simulator.engine in ("analytic", "mujoco") else None
    if instances is not None:
        assert len(instances) == config.instances.count
    assert parse_config(yaml.safe_load(dump_config(config))) == config
    given_value = data
    for part in path.split("."):
        given_value = given_value[part]
    parsed = parsed_value(config, path)
    expect = numbers_in(given_value)
    if expect is not None and not isinstance(parsed, (str, BaseModel)):
        got = numbers_in(list(parsed) if isinstance(parsed, (list, tuple)) else parsed)
        assert got == expect, (path, given_value, parsed)


@pytest.mark.parametrize("contexts", [[[]], [[1.0]]])
def test_contexts_for_a_family_without_context_are_refused(contexts):
    # [[]] once passed validation for insertion and then crashed drawing the instances.
    with pytest.raises(ConfigError, match=r"^invalid config field 'instances.contexts'.*insertion family has no context"):
        parse_config({"instances": {"count": 4, "contexts": contexts}})


@settings(max_examples=600, **SETTINGS)
@given(data=st.data())
def test_config_field_gets_a_valid_value_or_a_one_line_error_naming_it(data):
    path = data.draw(st.sampled_from(FIELDS), label="path")
    value = data.draw(st.one_of(near_valid(path), values), label="value")
    check_config_outcome(nest(path, value), path)


@settings(max_examples=100, **SETTINGS)
@given(key=st.text(min_size=1, max_size=10), section=st.sampled_from(["", "model.", "belief.", "probes."]), value=values)
def test_unknown_keys_are_named(key, section, value):
    known = set(FIELDS) | {f.split(".")[-1] for f in FIELDS}
    assume(key not in known)
    data = {section[:-1]: {key: value}} if section else {key: value}
    with pytest.raises(ConfigError) as err:
        parse_config(data)
    message = str(err.value)
    assert "\n" not in message and message.startswith(f"invalid config field '{section}")


@settings(max_examples=50, **SETTINGS)
@given(value=values)
def test_a_config_that_is_not_a_mapping_is_refused(value):
    assume(not isinstance(value, dict))
    with pytest.raises(ConfigError, match="^config must be a mapping of fields, got "):
        parse_config(value)


@settings(max_examples=150, **SETTINGS)
@given(text=st.one_of(
    st.text(max_size=200),
    st.binary(max_size=100).map(lambda b: b.decode("latin-1")),
    st.builds(lambda path, v: yaml.safe_dump(nest(path, v), allow_unicode=True), st.sampled_from(FIELDS), values),
    st.lists(st.sampled_from(["seed: 1", "seed: 2", "repeats: 3", "model:", "  sigma: 0.4", "  sigma: .nan",
                              "belief: {particles: 8}", "- 1", "name: [x", "\t", "probes: {budget: 2, budgets: [3]}",
                              "simulator:", "  engine: analytic", "&a x: *a", "? [1, 2]\n: 3", "!!python/object:os.system x"]),
             max_size=6).map("\n".join),
))
def test_config_file_gives_a_config_or_a_one_line_error_naming_the_file(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("cfg") / "study.yaml"
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    try:
        config = load_config(path)
    except ConfigError as exc:
        message = str(exc)
        assert "\n" not in message, repr(message)
        assert message.startswith(f"{path}: "), message
        return
    assert isinstance(config, StudyConfig)
    assert parse_config(yaml.safe_load(dump_config(config))) == config


def test_config_file_errors_say_where(tmp_path):
    cases = {
        "seed: 1\nseed: 2\n": "duplicate key 'seed'",
        "model:\n  sigma: 0.4\n  sigma: 0.5\n": "duplicate key 'sigma'",
        "name: [x\n": "not valid YAML at line 2",
        "0\n": "must be a mapping",
        "model: {sigma: .nan}\n": "invalid config field 'model.sigma': Input should be a finite number",
        "repeats: true\n": "invalid config field 'repeats': expected a number, got a boolean",
    }
    for text, expected in cases.items():
        path = tmp_path / "c.yaml"
        path.write_text(text)
        with pytest.raises(ConfigError) as err:
            load_config(path)
        assert str(err.value).startswith(f"{path}: ") and expected in str(err.value), (text, str(err.value))
    path.write_bytes(b"name: \xff\xfe\n")
    with pytest.raises(ConfigError, match="not UTF-8"):
        load_config(path)
    path.write_text("")
    assert load_config(path) == StudyConfig()


# --------------------------------------------------------------------------- tables

def probe_table() -> pd.DataFrame:
    rows = [(f"i{i}", r, j, float(3 * j - 6 + i), -15.0 * ((i + j + r) % 2) + 0.125 * j)
            for i in range(3) for r in range(2) for j in range(1, 4)]
    return pd.DataFrame(rows, columns=["instance_id", "repeat", "j", "u", "y"])


junk_cells = st.one_of(
    st.none(), st.booleans(), st.integers(-5, 5), st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from(["", "NaN", "nan", "inf", "-inf", "1.5", "2", "2.0", " 3 ", "abc", "1,5", "0x10", "1e400", "-0"]),
    st.text(max_size=6),
)


def mutate(table: pd.DataFrame, data, columns) -> pd.DataFrame:
    kind = data.draw(st.sampled_from(["cell", "cell", "cell", "drop_col", "drop_row", "dup_row", "rename", "none"]))
    df = table.copy().astype(object)
    if kind == "cell":
        for _ in range(data.draw(st.integers(1, 3))):
            row = data.draw(st.integers(0, len(df) - 1))
            col = data.draw(st.sampled_from(columns))
            df.iat[row, df.columns.get_loc(col)] = data.draw(junk_cells)
    elif kind == "drop_col":
        df = df.drop(columns=data.draw(st.sampled_from(columns)))
    elif kind == "drop_row":
        df = df.drop(index=data.draw(st.integers(0, len(df) - 1)))
    elif kind == "dup_row":
        df = pd.concat([df, df.iloc[[data.draw(st.integers(0, len(df) - 1))]]])
    elif kind == "rename":
        col = data.draw(st.sampled_from(columns))
        df = df.rename(columns={col: data.draw(st.sampled_from([col.upper(), f" {col} ", col + "_x"]))})
    return df.reset_index(drop=True)


def write_table(df: pd.DataFrame, path_stem: Path, fmt: str) -> Path:
    if fmt == "csv":
        path = path_stem.with_suffix(".csv")
        df.to_csv(path, index=False)
        return path
    path = path_stem.with_suffix(".parquet")
    out = df.copy()
    for col in out.columns:
        kinds = {type(v) for v in out[col] if v is not None}
        if len(kinds) > 1 or kinds & {str}:
            out[col] = out[col].map(lambda v: None if v is None else str(v))
    try:
        out.infer_objects().to_parquet(path, index=False)
    except Exception:  # noqa: BLE001 - a column pyarrow cannot store: store it as text
        out.astype(str).to_parquet(path, index=False)
    return path


def as_number(v) -> float:
    if isinstance(v, bool):
        return float("nan")
    try:
        return float(str(v).strip()) if isinstance(v, str) else float(v)
    except (TypeError, ValueError):
        return float("nan")


@settings(max_examples=200, **SETTINGS)
@given(data=st.data(), fmt=st.sampled_from(["csv", "parquet"]))
def test_probe_reader_names_the_column_or_row_or_reads_the_exact_numbers(tmp_path_factory, data, fmt):
    table = probe_table()
    bad = mutate(table, data, list(table.columns))
    path = write_table(bad, tmp_path_factory.mktemp("probes") / "probes", fmt)
    try:
        got = read_probes(path)
    except ProbeTableError as exc:
        message = str(exc)
        assert "\n" not in message
        assert str(path) in message
        assert any(w in message for w in ("column '", "row ", "missing required column", "no rows", "cannot read")), message
        return
    # Accepted: exactly the numbers in the file, in file order.
    reread = pd.read_csv(path, dtype=str, keep_default_na=False) if fmt == "csv" else pd.read_parquet(path)
    reread.columns = [c.strip() for c in reread.columns]
    for col in ("repeat", "j", "u", "y"):
        expect = np.array([as_number(v) for v in reread[col]])
        assert np.all(np.isfinite(expect)), (col, reread[col].tolist())
        np.testing.assert_array_equal(got[col].to_numpy(float), expect)
    assert len(got) == len(reread)


def test_probe_reader_messages(tmp_path):
    t = probe_table()
    cases = [
        (t.drop(columns="y"), "missing required column(s) y"),
        (t.assign(y=t.y.astype(object).where(t.index != 4, "abc")), "column 'y' must be numeric, found 'abc' at row 4 (CSV line 6)"),
        (t.assign(u=t.u.where(t.index != 2, np.nan)), "column 'u' is empty or NaN at row 2 (CSV line 4)"),
        (t.assign(j=t.j.astype(float).where(t.index != 1, 1.5)), "column 'j' must be an integer"),
        (t.drop(index=4), "has 2 probe(s) but j goes up to 3"),
        (t[t.j < 3].pipe(lambda d: pd.concat([d, t.iloc[[2]]])), "has 3 probe(s) but most have 2"),
        (pd.concat([t, t.iloc[[5]]]), "is given twice"),
    ]
    for frame, expected in cases:
        path = tmp_path / "p.csv"
        frame.to_csv(path, index=False)
        with pytest.raises(ProbeTableError) as err:
            read_probes(path)
        assert expected in str(err.value), (expected, str(err.value))


@settings(max_examples=200, **SETTINGS)
@given(ids=st.lists(st.sampled_from(["i0", "i1", " i1", "i1 ", "", "  ", "nan", "None", "7", None]), min_size=6, max_size=6))
def test_text_instance_ids_are_checked_once_per_distinct_id_as_row_by_row(ids):
    """A text column (Parquet, CSV) is checked per distinct id: same table or same message as the row-by-row check."""
    table = pd.DataFrame({"instance_id": ids, "repeat": range(6), "j": 1, "u": 0.5, "y": -1.0})
    outcomes = []
    for dtype in ("str", object):
        try:
            outcomes.append(validate_probes(table.astype({"instance_id": dtype}), "log"))
        except ProbeTableError as exc:
            outcomes.append(str(exc))
    text, by_row = outcomes
    if isinstance(by_row, str):
        assert text == by_row
    else:
        pd.testing.assert_frame_equal(text, by_row)
        assert [v for v in text["instance_id"]] == [str(v).strip() for v in ids]


# ------------------------------------------------------------------ audit reader

audit_io = pytest.importorskip("probecommit.audit.io")


@pytest.fixture(scope="module")
def episode_table(tmp_path_factory) -> pd.DataFrame:
    from probecommit.runner.study import run_study
    from tests.conftest import small_config

    cfg = small_config(instances={"count": 3}, probes={"budget": 2}, belief={"particles": 32}, blind_prior_samples=200)
    return run_study(cfg, tmp_path_factory.mktemp("ep") / "run").episodes


NUMERIC_REQUIRED = ("predicted", "realized", "z_true", "retained_lo", "retained_hi", "hull_lo", "hull_hi")


@settings(max_examples=200, **SETTINGS)
@given(data=st.data(), fmt=st.sampled_from(["csv", "parquet"]))
def test_episode_reader_names_the_column_or_row_or_reads_the_exact_numbers(tmp_path_factory, episode_table, data, fmt):
    columns = list(audit_io.AUDIT_REQUIRED) + ["status", "covered", "method"]
    bad = mutate(episode_table, data, columns)
    path = write_table(bad, tmp_path_factory.mktemp("episodes") / "episodes", fmt)
    try:
        got = audit_io.read_episodes(path)
    except audit_io.EpisodeTableError as exc:
        message = str(exc)
        assert "\n" not in message, message
        assert str(path) in message, message
        return
    reread = pd.read_csv(path, dtype=str, keep_default_na=False) if fmt == "csv" else pd.read_parquet(path)
    reread.columns = [c.strip() for c in reread.columns]
    ok = got["status"].to_numpy() == "ok"
    for col in NUMERIC_REQUIRED + ("repeat", "k"):
        expect = np.array([as_number(v) for v in reread[col]])
        np.testing.assert_array_equal(got[col].to_numpy(float)[ok], expect[ok], err_msg=col)
        assert np.all(np.isfinite(got[col].to_numpy(float)[ok])), col


@pytest.mark.parametrize("column,value", [("repeat", "inf"), ("k", "-inf"), ("repeat", "1.3e278")])
def test_episode_reader_refuses_non_finite_or_huge_integers(tmp_path, episode_table, column, value):
    """Found by the property test above: these reached ``astype(int64)`` (a pandas
    IntCastingNaNError, or a silent wrap to -9.2e18)."""
    bad = episode_table.astype(object)
    bad.iat[5, bad.columns.get_loc(column)] = value
    path = tmp_path / "episodes.csv"
    bad.to_csv(path, index=False)
    with pytest.raises(audit_io.EpisodeTableError, match=rf"column '{column}'.*row 5 \(CSV line 7\)"):
        audit_io.read_episodes(path)
