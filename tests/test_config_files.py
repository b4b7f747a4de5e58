"""Config files read as their writer meant them, or refused naming the file and the key: an
integer YAML reads in another base than the digits show, a key given twice (YAML keeps the
last alone), a value that holds itself, bytes that are not UTF-8 text, a folder; a schema error
names the file (or ``--config``) that set the key, among several. Through the package's reader
(``jointbench fit --configfile``, the named protocols' overlays) and a real dry run alike."""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from pathlib import Path

import pytest
from snakemake.cli import parse_config
from workflow_copy import ROOT, copy_workflow, run_snakemake

from jointbench import declared
from jointbench.configuration import config as study_config
from jointbench.ensembles.sensitivity import member_names

DEFAULT = ROOT / "config" / "config.yaml"


def _refused(path: Path) -> str:
    with pytest.raises(ValueError) as raised:
        study_config.read_config_file(path, f"config file {path}")
    return str(raised.value)


def _dry_run(folder: Path, *arguments: str):
    """A dry run of the workflow copied into ``folder``: returncode, messages."""
    folder.mkdir()
    copy_workflow(folder)
    run = run_snakemake(folder, "-n", *arguments, timeout=300)
    return run.returncode, run.stdout + run.stderr


@pytest.mark.parametrize(
    ("written", "read", "why"),
    [
        ("010", 8, "octal"),
        ("0x10", 16, "hexadecimal"),
        ("1_000", 1000, "drops the underscores"),
        ("0b11", 3, "binary"),
        ("1:30", 90, "base 60"),
        ("-010", -8, "octal"),
    ],
    ids=["octal", "hex", "underscore", "binary", "sexagesimal", "negative octal"],
)
def test_an_integer_yaml_reads_in_another_base_is_refused_naming_the_key_and_file(
    tmp_path, written, read, why
):
    path = tmp_path / "mine.yaml"
    path.write_text(f"base_seed: 3\nstudies:\n  cmc:\n    trials: {written}\n")
    message = _refused(path)
    for word in (str(path), "studies.cmc.trials", "line 4", written, f"as {read}", why):
        assert word in message, message


@pytest.mark.parametrize("written", ["1_000.5", "1:30.5"], ids=["underscore", "sexagesimal"])
def test_a_float_yaml_reads_otherwise_than_written_is_refused(tmp_path, written):
    path = tmp_path / "mine.yaml"
    path.write_text(f"blind_placement: {{translation_mm: {written}}}\n")
    message = _refused(path)
    assert "blind_placement.translation_mm" in message and written in message, message


@pytest.mark.parametrize(
    ("written", "read"), [('!!int "010"', 8), ("!!int '0x10'", 16), ('!!float "1_000.5"', 1000.5)]
)
def test_a_quoted_number_tagged_as_one_is_held_to_its_digits(tmp_path, written, read):
    path = tmp_path / "mine.yaml"
    path.write_text(f"studies:\n  cmc:\n    trials: {written}\n")
    message = _refused(path)
    for word in (str(path), "studies.cmc.trials", "line 3", f"as {read}"):
        assert word in message, message


@pytest.mark.parametrize(
    "written", ["10", "0", "-3", "+7", "1.5", "0.5", "1.0e+3", "'1e3'", "'010'"]
)
def test_numbers_in_decimal_digits_and_quoted_text_are_read(tmp_path, written):
    path = tmp_path / "mine.yaml"
    path.write_text(f"base_seed: {written}\n")
    assert study_config.read_config_file(path, "config file") == {
        "base_seed": study_config.read_yaml(written)
    }


def test_the_shipped_config_files_are_read_as_before():
    for path in [DEFAULT, *sorted((ROOT / "config" / "variants").glob("*.yaml"))]:
        expected = study_config.read_yaml(path.read_text())
        assert study_config.read_config_file(path, f"config file {path}") == expected


def test_a_key_given_twice_is_refused_naming_it_and_both_lines(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("studies:\n  cmc:\n    trials: 5\n    grid: {}\n    trials: 7\n")
    message = _refused(path)
    for word in (str(path), "studies.cmc.trials", "lines 3 and 5"):
        assert word in message, message


@pytest.mark.parametrize(
    "text",
    [
        "studies: {cmc: {trials: 5, trials: 7}}\n",
        "studies:\n  cmc: {trials: 5, grid: {}, trials: 7}\n",
    ],
    ids=["flow", "flow in block"],
)
def test_a_key_given_twice_on_one_line_is_refused(tmp_path, text):
    path = tmp_path / "mine.yaml"
    path.write_text(text)
    message = _refused(path)
    line = text.count("\n", 0, text.index("trials")) + 1
    for word in (str(path), "studies.cmc.trials", f"twice on line {line}"):
        assert word in message, message


@pytest.mark.parametrize(
    ("first", "then"),
    [
        ("yes", "true"),
        ("on", "True"),
        ("1", "1.0"),
        ("true", "1"),
        ("null", "~"),
        (".nan", ".NaN"),
        ("0o", "'0o'"),
    ],
    ids=["yes true", "on True", "1 1.0", "true 1", "null ~", "nan NaN", "same text, one quoted"],
)
def test_keys_written_apart_that_read_as_one_are_refused_naming_both_lines(tmp_path, first, then):
    # YAML 1.1 reads yes, on and true as True, and Python's mapping holds True, 1 and 1.0 as
    # one key: the first value would be dropped without a word, as with a key written twice.
    path = tmp_path / "mine.yaml"
    path.write_text(f"studies:\n  cmc:\n    {first}: 5\n    grid: {{}}\n    {then}: 7\n")
    message = _refused(path)
    for word in (str(path), f"studies.cmc.{first}", "twice, at lines 3 and 5"):
        assert word in message, message
    # Written apart, each is named as written (test_keys_read_alike_are_named_as_each_reads).
    assert (f" (as {first} and {then}, " in message) == (then.strip("'") != first), message


@pytest.mark.parametrize(
    ("first", "then", "words"),
    [
        ("yes", "true", "(as yes and true, both read as True)"),
        ("true", "1", "(as true and 1, read as True and 1, which a mapping holds as one key)"),
        ("1", "1.0", "(as 1 and 1.0, read as 1 and 1.0, which a mapping holds as one key)"),
    ],
)
def test_keys_read_alike_are_named_as_each_reads(tmp_path, first, then, words):
    # true is not read as 1, nor 1 as 1.0: they are equal, and a mapping holds them as one key.
    path = tmp_path / "mine.yaml"
    path.write_text(f"a:\n  {first}: 5\n  {then}: 7\n")
    assert words in _refused(path)


def test_keys_that_only_look_alike_are_read(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("a:\n  yes: 1\n  'yes': 2\n  2: 3\n  '2': 4\n  2.5: 5\n  '2.5': 6\n")
    read = study_config.read_config_file(path, f"config file {path}")
    assert len(read["a"]) == 6, read


def test_the_key_written_as_an_equals_sign_is_read_as_text(tmp_path):
    # YAML 1.1 tags a plain = with its "value" tag, which the safe loader reads, as a key, as
    # the text '='.
    path = tmp_path / "mine.yaml"
    path.write_text("a:\n  =: 1\n  b: 2\n")
    assert study_config.read_config_file(path, f"config file {path}") == {"a": {"=": 1, "b": 2}}
    path.write_text("a:\n  =: 1\n  '=': 2\n")
    message = _refused(path)
    for word in (str(path), "a.= is given twice, at lines 2 and 3"):
        assert word in message, message


@pytest.mark.parametrize("tag", ["!!set", "!!seq", "!!map", "!!omap"])
def test_a_key_tagged_as_a_collection_is_refused_naming_the_file(tmp_path, tag):
    path = tmp_path / "mine.yaml"
    path.write_text(f"a:\n  {tag} k: 1\n")
    message = _refused(path)
    for word in (str(path), "not valid YAML at line 2", "unhashable key"):
        assert word in message, message


@pytest.mark.parametrize("written", ["010", "0x10", "1_000"])
def test_a_key_yaml_reads_as_another_number_is_refused(tmp_path, written):
    path = tmp_path / "mine.yaml"
    path.write_text(f"studies:\n  cmc:\n    {written}: 3\n")
    message = _refused(path)
    for word in (str(path), f"studies.cmc.{written}", "line 3", f"{written} is read as"):
        assert word in message, message


@pytest.mark.parametrize(
    ("text", "keys", "line"),
    [
        ("studies:\n  cmc:\n    trials: 2020-02-30\n", "studies.cmc.trials", 3),
        ("sensitivity:\n  named:\n    2021-13-01: mine.yaml\n", "sensitivity.named.2021-13-01", 3),
    ],
    ids=["value", "key"],
)
def test_a_date_that_is_no_date_is_refused_naming_the_key_and_file(tmp_path, text, keys, line):
    # YAML 1.1 reads the digits of a date as one; the day or month out of range fails in the
    # reader with Python's words alone, naming neither the file nor the key.
    path = tmp_path / "mine.yaml"
    path.write_text(text)
    message = _refused(path)
    for word in (str(path), f"{keys} at line {line}", "is read as a date, and is none ("):
        assert word in message, message


def test_a_value_that_holds_itself_is_refused(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("studies:\n  cmc: &loop\n    grid: *loop\n")
    message = _refused(path)
    assert str(path) in message and "studies.cmc.grid" in message and "line 3" in message, message


def test_text_that_is_not_utf8_is_refused_naming_the_byte_and_line(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_bytes(b"base_seed: 3\n# caf\xe9\n")
    message = _refused(path)
    assert str(path) in message and "UTF-8" in message and "line 2" in message, message
    binary = tmp_path / "binary.yaml"
    binary.write_bytes(b"\x00\x01\xff\xfe")
    assert "UTF-8" in _refused(binary)


def test_a_folder_is_refused_as_one(tmp_path):
    assert "a folder, not a file" in _refused(tmp_path)


def test_a_schema_error_names_the_file_that_set_the_key(tmp_path):
    first, second = tmp_path / "a.yaml", tmp_path / "b.yaml"
    first.write_text("studies: {cmc: {trials: 0}}\n")
    second.write_text("base_seed: 3\n")
    with pytest.raises(ValueError) as raised:
        study_config.read_configs([DEFAULT, first, second])
    message = str(raised.value)
    assert "studies/cmc/trials" in message and f"set in {first}" in message, message
    assert str(second) not in message and str(DEFAULT) not in message, message


def test_a_misspelt_key_names_the_file_that_holds_it(tmp_path):
    first = tmp_path / "a.yaml"
    first.write_text("blind_placement: {translation_mm: 400.0}\n")
    second = tmp_path / "b.yaml"
    second.write_text("blind_placement: {rotation: true}\n")
    with pytest.raises(ValueError) as raised:
        study_config.read_configs([DEFAULT, first, second])
    message = str(raised.value)
    assert "rotation" in message and f"set in {second})" in message, message
    assert str(first) not in message, message


def test_a_mapping_at_fault_names_every_file_that_merged_into_it(tmp_path):
    first, second, third = (tmp_path / f"{name}.yaml" for name in "abc")
    first.write_text("studies: {toy: {trials: 2}}\n")
    second.write_text("base_seed: 3\n")
    third.write_text("studies: {toy: {enabled: true}}\n")
    with pytest.raises(ValueError) as raised:
        study_config.read_configs([DEFAULT, first, second, third])
    message = str(raised.value)
    assert "'toy'" in message and f"(set in {first}, {third})" in message, message


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("studies:\n  cmc:\n    trials: 010\n", ["studies.cmc.trials", "line 3", "as 8"]),
        (
            "studies:\n  cmc:\n    trials: 5\n    trials: 7\n",
            ["studies.cmc.trials", "lines 3 and 4"],
        ),
    ],
    ids=["octal", "twice"],
)
def test_dry_run_refuses_a_config_file_read_otherwise_than_written(tmp_path, text, words):
    overlay = tmp_path / "mine.yaml"
    overlay.write_text(text)
    code, message = _dry_run(tmp_path / "wf", "--configfile", str(overlay))
    assert code != 0 and "Job stats" not in message, message[-2000:]
    for word in [str(overlay), *words]:
        assert word in message, message[-2000:]


@pytest.mark.parametrize("value", ["010", "1_000"])
def test_dry_run_refuses_a_config_value_read_otherwise_than_written(tmp_path, value):
    code, message = _dry_run(tmp_path / "wf", "--config", f"base_seed={value}")
    assert code != 0 and "Job stats" not in message, message[-2000:]
    assert f"--config base_seed={value}" in message, message[-2000:]


def test_dry_run_names_the_config_file_of_a_schema_error(tmp_path):
    first, second = tmp_path / "a.yaml", tmp_path / "b.yaml"
    first.write_text("studies: {cmc: {trials: 0}}\n")
    second.write_text("base_seed: 3\n")
    code, message = _dry_run(tmp_path / "wf", "--configfile", str(first), str(second))
    assert code != 0 and "Job stats" not in message, message[-2000:]
    assert "studies/cmc/trials" in message and f"set in {first}" in message, message[-2000:]
    code, message = _dry_run(tmp_path / "wf2", "--config", "verdicts={'seeds': 0}")
    assert code != 0 and "verdicts/seeds" in message, message[-2000:]
    assert "set in --config" in message, message[-2000:]


@pytest.mark.parametrize("value", ["010.5", "00.5", "-07.25", "0", "-0", "0.0", "10"])
def test_a_config_value_read_as_its_digits_show_is_not_refused(value):
    study_config.check_config_values([f"base_seed={value}", f"label=v{value}"])


@pytest.mark.parametrize("value", ["010", "-010", "1_000", "1_000.5", "0_1.5"])
def test_a_config_value_read_otherwise_than_written_is_refused(value):
    with pytest.raises(ValueError, match=f"--config base_seed={value}: {value} is read as"):
        study_config.check_config_values([f"base_seed={value}"])


@pytest.mark.parametrize("written", ["1e-3", "2E5", "-1e3", "+5e0"])
def test_an_exponent_without_a_dot_yaml_reads_as_text_is_refused(tmp_path, written):
    # YAML 1.1 (PyYAML's, Snakemake's) reads 1e-3 as the text '1e-3', not a number; in a
    # field that takes text it would pass for a name.
    path = tmp_path / "mine.yaml"
    path.write_text(f"studies:\n  cmc:\n    protocol:\n      noise_mm: {written}\n")
    message = _refused(path)
    for word in (str(path), "studies.cmc.protocol.noise_mm", "line 4", written, "text", "dot"):
        assert word in message, message


@pytest.mark.parametrize("written", ["1.0e3", "2.5E7", "1e3", "-.5", "+.5e-3", "1.e2", "7e-1"])
def test_a_number_yaml_1_1_reads_as_text_is_refused_with_a_rewrite_it_reads(tmp_path, written):
    # YAML 1.1 takes an exponent only after a dot and with its sign, and a sign only before a
    # digit: 1.0e3, the rewrite a dot alone suggests, is the text '1.0e3' too, and was refused
    # only as no number, without a word on why or how to write it.
    path = tmp_path / "mine.yaml"
    path.write_text(f"studies:\n  cmc:\n    protocol:\n      noise_mm: {written}\n")
    message = _refused(path)
    for word in (str(path), "studies.cmc.protocol.noise_mm", "line 4", f"the text {written!r}"):
        assert word in message, message
    rewrite = re.search(r"write it as (\S+?),", message).group(1)
    assert study_config.read_yaml(rewrite) == float(written), message


def test_a_json_config_file_is_read_as_json_as_snakemake_reads_it(tmp_path):
    # Snakemake reads a config file as JSON first, where 1e-3 is a number and 010 no number.
    path = tmp_path / "mine.json"
    path.write_text('{"studies": {"cmc": {"protocol": {"noise_mm": 1e-3}, "trials": 3}}}')
    read = study_config.read_config_file(path, "config file")
    assert read == {"studies": {"cmc": {"protocol": {"noise_mm": 0.001}, "trials": 3}}}


def test_a_key_given_twice_in_a_json_config_file_is_refused(tmp_path):
    path = tmp_path / "mine.json"
    path.write_text('{"studies": {"cmc": {"trials": 3, "trials": 5}}}')
    message = _refused(path)
    assert str(path) in message and "'trials'" in message and "twice" in message, message


@pytest.mark.parametrize(
    ("text", "keys"),
    [
        ('{"studies": {"cmc": {"trials": 3, "trials": 5}}}', "studies.cmc.trials"),
        ('{"a": [1, {"b": {"c": 1, "c": 2}}]}', "a[1].b.c"),
        ('{"a": {"x": 1}, "b": {"x": 1, "x": 2}}', "b.x"),
        ('{"a": {"k": 1, "k": 2}, "b": {"j": 1, "j": 2}}', "a.k"),
        ('{"a": {"k": 1, "j": 1, "k": 2, "j": 2}}', "a.k"),
    ],
)
def test_a_key_given_twice_in_a_json_config_file_is_named_by_its_path(tmp_path, text, keys):
    path = tmp_path / "mine.json"
    path.write_text(text)
    assert f"{path}: {keys} is given twice in one object" in _refused(path)


# A mistake after the schema's check, of each kind of check, and the overlay setting it: a
# first overlay over the config sets keys of the same study, a second the one at fault.
AFTER_SCHEMA = {
    "grid value": (
        "studies: {cmc: {grid: {rom_deg: [0]}}}\n",
        ["studies.cmc.grid.rom_deg: 0 is not allowed"],
    ),
    "protocol field": (
        "studies: {hip: {protocol: {fps: 0}}}\n",
        ["studies.hip.protocol.fps: must be a number > 0"],
    ),
    "motion short of its rom": (
        "studies: {hinge: {protocol: {all: {motion: lissajous, fe_cycles: 1.0e-300}}}}\n",
        ["studies.hinge.protocol.all.fe_cycles: 1e-300 knee lissajous FE cycles"],
    ),
    "hip rig about one axis": (
        "studies: {hip: {protocol: {cross_swing_deg: 0, twist_deg: 0}}}\n",
        ["studies.hip.protocol.swing_deg, cross_swing_deg, twist_deg", "only swing_deg"],
    ),
    "estimator option": (
        "studies: {cmc: {options: {BC: {tol_x: -1}}}}\n",
        ["studies.cmc.options.BC.tol_x: must be a number > 0, got -1"],
    ),
    "frames": (
        "studies: {hip: {grid: {n_frames: [1]}}}\n",
        ["studies.hip.grid.n_frames: condition n_frames-1 has trials of 1 frame(s)"],
    ),
    "estimator name": (
        "studies: {hip: {estimators: [SCoRE, XX]}}\n",
        ["studies.hip.estimators: unknown joint_center estimator 'XX'"],
    ),
}
# The first overlay: a key of each study, beside the one the second sets.
FIRST = "studies: {cmc: {trials: 3}, hinge: {trials: 3}, hip: {trials: 3}}\n"


def _overlays(folder: Path, second: str) -> tuple[Path, Path]:
    first_path, second_path = folder / "a.yaml", folder / "b.yaml"
    first_path.write_text(FIRST)
    second_path.write_text(second)
    return first_path, second_path


@pytest.mark.parametrize("kind", AFTER_SCHEMA)
def test_a_mistake_after_the_schema_names_the_config_file_that_set_it(tmp_path, kind):
    text, words = AFTER_SCHEMA[kind]
    first, second = _overlays(tmp_path, text)
    with pytest.raises(ValueError) as raised:
        study_config.open_config_files([DEFAULT, first, second])
    message = str(raised.value)
    for word in [*words, f"(set in {second})"]:
        assert word in message, message
    assert str(first) not in message and str(DEFAULT) not in message, message


def test_a_mistake_at_keys_of_several_files_names_each_keys_file():
    """A bound across fields names the file that sets each of them, where they differ: the
    first's noise under ``all`` and the second's markers of the knee, not a third's keys."""
    sources = [
        ("base.yaml", {"studies": {"hinge": {"protocol": {"all": {"noise_sd_mm": 1e200}}}}}),
        ("over.yaml", {"studies": {"hinge": {"protocol": {"knee": {"markers_mm": [[0, 0, 1]]}}}}}),
        ("other.yaml", {"base_seed": 3}),
    ]
    error = study_config.ConfigError(
        "config: studies.hinge.protocol.all.noise_sd_mm, knee.markers_mm: too much",
        [
            ("studies", "hinge", "protocol", "all", "noise_sd_mm"),
            ("studies", "hinge", "protocol", "knee", "markers_mm"),
        ],
    )
    with pytest.raises(ValueError) as raised, study_config.sources_named(sources):
        raise error
    assert str(raised.value).endswith(
        "too much (studies.hinge.protocol.all.noise_sd_mm set in base.yaml; knee.markers_mm set "
        "in over.yaml)"
    ), raised.value


@pytest.mark.parametrize(
    ("second", "named"),
    [
        ({"fps": 50.0, "swing_hz": 0.1}, "(set in over.yaml)"),
        ({"fps": 50.0}, "(set in over.yaml)"),
        (
            {"swing_hz": 0.1},
            "(studies.hip.protocol.swing_hz set in over.yaml; fps set in base.yaml)",
        ),
    ],
    ids=["one file sets both", "a default beside", "each its own"],
)
def test_a_mistake_at_several_keys_names_only_the_files_that_set_them(second, named):
    """Keys set by one file, beside any no file sets (a default), are named as that file's;
    keys set by different files, each with its own, and no file that sets neither."""
    sources = [
        ("base.yaml", {"studies": {"hip": {"protocol": {"fps": 60.0}}}}),
        ("over.yaml", {"studies": {"hip": {"protocol": second}}}),
        ("other.yaml", {"base_seed": 3}),
    ]
    error = study_config.ConfigError(
        "config: studies.hip.protocol.swing_hz, fps: too fast",
        [("studies", "hip", "protocol", "swing_hz"), ("studies", "hip", "protocol", "fps")],
    )
    with pytest.raises(ValueError) as raised, study_config.sources_named(sources):
        raise error
    assert str(raised.value) == f"config: studies.hip.protocol.swing_hz, fps: too fast {named}"


@pytest.mark.parametrize(
    ("paths", "keys"),
    [
        ([("studies", "cmc", "trials")], "studies.cmc.trials"),
        ([("studies", "cmc", "options", "MA", "start", 2)], "studies.cmc.options.MA.start[2]"),
        (
            [("studies", "hip", "protocol", "swing_hz"), ("studies", "hip", "protocol", "fps")],
            "studies.hip.protocol.swing_hz, fps",
        ),
        (
            [
                ("studies", "hinge", "protocol", "all", "noise_sd_mm"),
                ("studies", "hinge", "protocol", "knee", "markers_mm"),
            ],
            "studies.hinge.protocol.all.noise_sd_mm, knee.markers_mm",
        ),
        (
            [
                ("studies", "hinge", "protocol", "all", "markers_mm", 0),
                ("studies", "hinge", "protocol", "all", "noise_sd_mm"),
            ],
            "studies.hinge.protocol.all.markers_mm[0], noise_sd_mm",
        ),
        # A path all of whose keys the first holds keeps its last.
        (
            [("studies", "hip", "protocol", "fps"), ("studies", "hip", "protocol")],
            "studies.hip.protocol.fps, protocol",
        ),
    ],
)
def test_the_paths_a_refusal_is_at_are_written_as_its_keys(paths, keys):
    assert declared.keys(paths) == keys


def test_a_declaration_error_put_under_outer_keys_puts_each_of_its_paths_there():
    error = declared.DeclarationError(("noise_mm",), "too large", [("markers_mm", 0)])
    assert error.under("protocol").paths == (
        ("protocol", "noise_mm"),
        ("protocol", "markers_mm", 0),
    )
    assert str(error.under("protocol")) == "protocol.noise_mm, markers_mm[0]: too large"


# Keys a user names (a joint of the hinge protocol) holding what a key path's text is made of.
ODD_KEYS = ["knee.v2", "a, b", "x[0]", "[1]"]


@pytest.mark.parametrize("joint", ODD_KEYS)
def test_a_mistake_under_a_key_holding_a_dot_comma_or_bracket_names_its_config_file(
    tmp_path, joint
):
    first, second = _overlays(
        tmp_path, f"studies: {{hinge: {{protocol: {{{json.dumps(joint)}: {{n_frames: 2}}}}}}}}\n"
    )
    with pytest.raises(ValueError) as raised:
        study_config.open_config_files([DEFAULT, first, second])
    message = str(raised.value)
    assert f"studies.hinge.protocol.{joint}.n_frames: must be an integer >= 4" in message, message
    assert message.endswith(f"(set in {second})"), message


# A refusal of a setting of the run's, not of a study's, and the second overlay setting it.
RUN_SETTINGS = {
    "time limit": (
        "jobs: {external_time_limit_s: .inf}\n",
        "config: jobs.external_time_limit_s: inf is not a number of seconds in (0, 604800]",
    ),
    "extension": (
        "extensions: [gone.py]\n",
        "config error at extensions: 'gone.py' is not a file",
    ),
}


@pytest.mark.parametrize("kind", RUN_SETTINGS)
def test_a_refusal_of_a_runs_setting_names_the_config_file_that_set_it(tmp_path, kind):
    text, words = RUN_SETTINGS[kind]
    first, second = _overlays(tmp_path, text)
    with pytest.raises(ValueError) as raised:
        study_config.open_config_files([DEFAULT, first, second], tmp_path)
    message = str(raised.value)
    assert words in message and message.endswith(f"(set in {second})"), message


def _named_overlays_refusal(folder: Path, overlay: Path) -> tuple[str, Path]:
    """The refusal of the named protocol ``mine`` at ``overlay``, named by the second of two
    config files over the default, and that file."""
    first, second = _overlays(folder, f"sensitivity: {{named: {{mine: {overlay}}}}}\n")
    sources = study_config.read_sources([DEFAULT, first, second])
    with pytest.raises(ValueError) as raised, study_config.sources_named(sources):
        study_config.named_overlays(study_config.merged_sources(sources))
    message = str(raised.value)
    assert message.startswith(f"config error at sensitivity.named.mine ({overlay}): "), message
    return message, second


@pytest.mark.parametrize(
    ("written", "words"),
    [
        (None, "no such file"),
        ("studies: {cmc: {trials: 3, trials: 4}}\n", "studies.cmc.trials is given twice"),
    ],
    ids=["missing", "refused as read"],
)
def test_a_named_protocols_refusal_names_the_config_file_that_named_it(tmp_path, written, words):
    overlay = tmp_path / "mine.yaml"
    if written is not None:
        overlay.write_text(written)
    message, second = _named_overlays_refusal(tmp_path, overlay)
    assert words in message and message.endswith(f"(set in {second})"), message


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("studies: {cmc: {trials: 0}}\n", "studies/cmc/trials: 0 is less than the minimum of 1"),
        ("studies: {cmc: {grid: {rom_deg: [0]}}}\n", "studies.cmc.grid.rom_deg: 0 is not allowed"),
    ],
)
def test_a_named_protocols_refusal_names_the_overlay_and_the_config_file_that_named_it(
    tmp_path, text, words
):
    # The key at fault is the overlay's, the key naming the overlay the config file's: each
    # named with its own file, so that neither reads as set where it is not.
    overlay = tmp_path / "mine.yaml"
    overlay.write_text(text)
    message, second = _named_overlays_refusal(tmp_path, overlay)
    assert f"{words}" in message and f"(set in {overlay})" in message, message
    assert message.endswith(f"(sensitivity.named.mine set in {second})"), message


@pytest.mark.parametrize("name", ["default", "draw-2", "draw-1.v2, x[0]"])
def test_a_named_protocol_named_as_the_default_or_a_draw_names_the_config_file_naming_it(
    tmp_path, name
):
    named = ROOT / "config" / "variants" / "hinge_anatomical_knee.yaml"
    first, second = _overlays(
        tmp_path, f"sensitivity: {{named: {json.dumps({name: str(named)})}}}\n"
    )
    sources = study_config.read_sources([DEFAULT, first, second])
    with pytest.raises(ValueError) as raised, study_config.sources_named(sources):
        overlays = study_config.named_overlays(study_config.merged_sources(sources))
        member_names("hinge", 2, overlays)
    message = str(raised.value)
    assert message.startswith(f"config: sensitivity.named.{name}: named protocol "), message
    assert message.endswith(f"(set in {second})"), message


@pytest.mark.pipeline
@pytest.mark.parametrize(
    ("kind", "text", "words"),
    [
        ("time limit", *RUN_SETTINGS["time limit"]),
        ("extension", *RUN_SETTINGS["extension"]),
        (
            "named protocol",
            "sensitivity: {named: {mine: config/variants/gone.yaml}}\n",
            "config error at sensitivity.named.mine (config/variants/gone.yaml): no such file",
        ),
        (
            "named as a drawn protocol",
            "sensitivity: {named: {draw-3: config/variants/hinge_anatomical_knee.yaml}}\n",
            "config: sensitivity.named.draw-3: named protocol 'draw-3' takes the name of a "
            "default or drawn one",
        ),
    ],
)
def test_dry_run_names_the_config_file_of_a_refused_run_setting(tmp_path, kind, text, words):
    first, second = _overlays(tmp_path, text)
    code, message = _dry_run(tmp_path / "wf", "--configfile", str(first), str(second))
    assert code != 0 and "Job stats" not in message, message[-2000:]
    for word in (words, f"(set in {second})"):
        assert word in message, message[-2000:]


@pytest.mark.pipeline
@pytest.mark.parametrize(
    "kind", ["grid value", "hip rig about one axis", "estimator option", "protocol field"]
)
def test_dry_run_names_the_config_file_of_a_mistake_after_the_schema(tmp_path, kind):
    text, words = AFTER_SCHEMA[kind]
    first, second = _overlays(tmp_path, text)
    code, message = _dry_run(tmp_path / "wf", "--configfile", str(first), str(second))
    assert code != 0 and "Job stats" not in message, message[-2000:]
    for word in [*words, f"(set in {second})"]:
        assert word in message, message[-2000:]
    assert f"(set in {first}" not in message, message[-2000:]


@pytest.mark.pipeline
def test_dry_run_names_the_config_file_listing_an_external_estimator_of_another_kind(tmp_path):
    first, second = _overlays(tmp_path, "studies: {hinge: {external_estimators: [centroid]}}\n")
    code, message = _dry_run(tmp_path / "wf", "--configfile", str(first), str(second))
    assert code != 0 and "Job stats" not in message, message[-2000:]
    for word in ["studies.hinge.external_estimators: 'centroid' writes center", str(second)]:
        assert word in message, message[-2000:]
    assert f"(set in {second})" in message, message[-2000:]


def test_a_study_name_the_schema_refuses_names_the_file_that_wrote_it(tmp_path):
    # The key at fault is the study's name, which one file writes: not `studies`, which every
    # config file sets.
    study = "{trials: 4, grid: {noise_mm: [0.5]}, estimators: [NM]}"
    first, second = _overlays(
        tmp_path, f"extensions: [lab_study.py]\nstudies: {{lab.v2: {study}}}\n"
    )
    sources = study_config.read_sources([DEFAULT, first, second])
    with pytest.raises(ValueError) as raised:
        study_config.check_sources(study_config.merged_sources(sources), sources)
    message = str(raised.value)
    assert "'lab.v2' does not match" in message, message
    assert message.endswith(f"(set in {second})"), message
    # Its name is the mistake, not where the study comes from.
    assert "not a built-in study" not in message, message


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("'': 1\n'': 2\n", "'' is given twice, at lines 1 and 2"),
        ('"": 1\n"": 2\n', "'' is given twice, at lines 1 and 2"),
        ("studies:\n  '': 1\n  ' ': 2\n  ' ': 3\n", "studies.' ' is given twice, at lines 3 and 4"),
        ("'':\n  '': {a: 1, a: 2}\n", "''.''.a is given twice on line 2"),
        ("'':\n  trials: 010\n", "config file {}: ''.trials at line 2: 010 is read as 8"),
        ('{"": 1, "": 2}', "'' is given twice in one object (the key '')"),
    ],
    ids=["single quotes", "double quotes", "blank", "under a blank key", "octal", "json"],
)
def test_a_blank_key_is_named_so_a_reader_can_find_it(tmp_path, text, words):
    path = tmp_path / "mine.yaml"
    path.write_text(text)
    assert words.format(path) in _refused(path)


def _study_name_refused(tmp_path: Path, text: str) -> str:
    first, second = _overlays(tmp_path, text)
    with pytest.raises(ValueError) as raised:
        study_config.open_config_files([DEFAULT, first, second])
    return str(raised.value)


STUDY = "{trials: 4, grid: {noise_mm: [0.5]}, estimators: [NM]}"


@pytest.mark.parametrize("name", ["knee.v2", "knee-v2", "knee v2", "2knee", "_knee"])
@pytest.mark.parametrize("extensions", ["", "extensions: [lab_study.py]\n"], ids=["", "extension"])
def test_a_study_name_no_study_may_have_is_named_with_the_rule_and_its_file(
    tmp_path, name, extensions
):
    message = _study_name_refused(tmp_path, f"{extensions}studies: {{'{name}': {STUDY}}}\n")
    assert f"config error at studies: {name!r} does not match" in message, message
    # What a name may be, in words; not an unknown study, which any name would then be.
    assert "a study's name is a letter, then letters, digits or underscores" in message, message
    assert "unknown studies" not in message and "not a built-in" not in message, message
    assert message.endswith(f"(set in {tmp_path / 'b.yaml'})"), message


def test_a_study_name_that_may_be_one_but_is_not_registered_is_named_unknown(tmp_path):
    message = _study_name_refused(tmp_path, f"studies: {{knee_v2: {STUDY}}}\n")
    assert "config error at studies: unknown studies ['knee_v2']" in message, message


def _config_values(*entries: str) -> dict:
    """The ``--config`` values ``entries`` as the workflow reads them: Snakemake's reading,
    each number in a mapping or list read as one."""
    return study_config.config_values(entries, parse_config(list(entries)))


def _opened_with(values: dict) -> Mapping:
    sources = [*study_config.read_sources([DEFAULT]), ("--config", values)]
    with study_config.sources_named(sources):
        return study_config.open_config(study_config.merged_sources(sources))


@pytest.mark.parametrize(
    ("entry", "path", "value"),
    [
        ("studies={cmc: {protocol: {n_frames: 700}}}", ("cmc", "protocol", "n_frames"), 700),
        ('studies={"cmc": {"trials": 7}}', ("cmc", "trials"), 7),
        ("studies={hinge: {protocol: {knee: {noise_sd_mm: 0.5}}}}", ("hinge", "protocol"), None),
        ("studies={cmc: {enabled: false}}", ("cmc", "enabled"), False),
        ("studies={cmc: {grid: {noise_mm: [0.5, 1]}}}", ("cmc", "grid", "noise_mm"), [0.5, 1]),
        ("studies={hip: {grid: {n_frames: [8, 16]}}}", ("hip", "grid", "n_frames"), [8, 16]),
    ],
    ids=["protocol", "json", "nested protocol", "boolean", "list", "ints"],
)
def test_a_number_written_in_a_config_value_is_checked_as_that_number(entry, path, value):
    values = _config_values(entry)
    opened = _opened_with(values)
    found = opened["studies"]
    for key in path:
        found = found[key]
    if value is not None:
        assert found == value and type(found) is type(value), found
    else:
        assert found["knee"]["noise_sd_mm"] == 0.5, found


def test_config_values_given_twice_keep_the_last_as_written():
    values = _config_values("studies={cmc: {trials: 3}}", "studies={hip: {trials: '4'}}")
    assert values == {"studies": {"cmc": {"trials": 3}, "hip": {"trials": "4"}}}
    values = _config_values("studies={cmc: {trials: 3}}", "studies={cmc: {trials: '5'}}")
    assert values == {"studies": {"cmc": {"trials": "5"}}}
    assert _config_values("base_seed=3", "base_seed=text") == {"base_seed": "text"}
    assert _config_values("verdicts={seeds: 2}", "verdicts=") == {"verdicts": None}


@pytest.mark.parametrize(
    ("entry", "text"),
    [
        ("base_seed=7mm", "7mm"),
        ("studies={cmc: {trials: '7'}}", "7"),
        ("studies={cmc: {protocol: {n_frames: 700 frames}}}", "700 frames"),
        ("studies={hinge: {protocol: {knee: {noise_sd_mm: '0.5'}}}}", "0.5"),
        ("studies={cmc: {grid: {noise_mm: [0.5, '1.0']}}}", "1.0"),
    ],
    ids=["unit", "quoted", "unit in a mapping", "quoted in a protocol", "quoted in a list"],
)
def test_a_config_value_left_as_text_is_refused_saying_so_and_how_to_write_a_number(entry, text):
    with pytest.raises(ValueError) as raised:
        _opened_with(_config_values(entry))
    message = str(raised.value)
    assert f"(set in --config, as the text {text!r}:" in message, message
    assert "a number is read from --config where it is written alone, unquoted" in message


@pytest.mark.parametrize(
    ("entry", "words"),
    [
        ("studies={cmc: {trials: 010}}", "cmc.trials at line 1: 010 is read as 8"),
        ("studies={cmc: {trials: 3, trials: 4}}", "cmc.trials is given twice on line 1"),
        ("studies={cmc: {options: {NM: {tol: 1e-3}}}}", "write it as 1.0e-3"),
        ("studies={cmc: {trials: !!int seven}}", "seven is tagged as a number (int), and is none"),
    ],
    ids=["octal", "twice", "exponent", "no such integer"],
)
def test_a_config_value_read_otherwise_than_written_in_a_mapping_is_refused(entry, words):
    with pytest.raises(ValueError) as raised:
        _config_values(entry)
    assert str(raised.value).startswith(f"--config {entry}: "), raised.value
    assert words in str(raised.value), raised.value


def test_a_text_value_that_is_no_number_is_named_as_before():
    with pytest.raises(ValueError) as raised:
        _opened_with(_config_values("studies={cmc: {estimators: [NM, XX]}}"))
    assert "as the text" not in str(raised.value), raised.value


@pytest.mark.parametrize(
    "arguments",
    [
        ["--config", "studies={cmc: {protocol: {n_frames: 700}}, hip: {trials: 5}}"],
        ["--config", "verdicts={seeds: 3}", "base_seed=7"],
        ["--profile", "mine"],
    ],
    ids=["mapping", "two values", "profile"],
)
def test_dry_run_reads_a_number_in_a_config_mapping_as_the_number(tmp_path, arguments):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "config.yaml").write_text('config:\n  - "studies={cmc: {trials: 7}}"\n')
    if arguments[0] == "--profile":
        arguments = ["--profile", str(tmp_path / "mine")]
    code, message = _dry_run(tmp_path / "wf", *arguments)
    assert code == 0 and "Job stats" in message, message[-2000:]


def test_dry_run_refuses_a_config_value_left_as_text_saying_so(tmp_path):
    code, message = _dry_run(tmp_path / "wf", "--config", "studies={cmc: {trials: 7 trials}}")
    assert code != 0 and "Job stats" not in message, message[-2000:]
    assert "(set in --config, as the text '7 trials':" in message, message[-2000:]


@pytest.mark.parametrize(
    ("written", "tag"), [("!!int seven", "int"), ("!!float abc", "float"), ("!!int 1.5", "int")]
)
def test_a_value_tagged_as_a_number_that_is_none_is_refused_naming_the_key(tmp_path, written, tag):
    path = tmp_path / "mine.yaml"
    path.write_text(f"studies:\n  cmc:\n    trials: {written}\n")
    message = _refused(path)
    value = written.split()[1]
    assert f"studies.cmc.trials at line 3: {value} is tagged as a number ({tag}), and is none" in (
        message
    ), message
