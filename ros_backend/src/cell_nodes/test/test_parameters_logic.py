"""Parameters, the plain-Python logic (no ROS): each type's validation and its message, the cell-file section, the
CSV round trip with every type (commas, quotes, newlines and unicode in strings; floats as written), missing and
corrupt files, the all-or-nothing set and its diff, the backup and the atomic write (a failing write leaves the old
file intact), hand edits picked up, and the reader other nodes use."""
from __future__ import annotations

import copy
import errno
import os
from pathlib import Path

import pytest
import yaml

from cell_nodes.parameters import ConfigError, read_parameters, read_values
from cell_nodes.parameters import csvfile
from cell_nodes.parameters.config import parse_parameters
from cell_nodes.parameters.csvfile import COLUMNS, read_csv, render, write_csv
from cell_nodes.parameters.store import ParameterStore
from cell_nodes.parameters.values import InvalidValue, ParamDef, canonical
from said_check import check_said

DEMO = Path(__file__).resolve().parents[4] / "config" / "demo-cell.yaml"

ITEMS = [
    {"category": "Motion", "label": "Approach height", "id": "approach_height", "type": "float", "unit": "mm",
     "min": 5, "max": 200, "default": 50},
    {"category": "Motion", "label": "Speed factor", "id": "speed_factor", "type": "float", "min": 0, "max": 1,
     "decimals": 2, "default": 0.5},
    {"category": "Motion", "label": "Tolerance", "id": "tolerance", "type": "float", "unit": "m", "default": 1.0e-5},
    {"category": "Process", "label": "Parts per cycle", "id": "parts_per_cycle", "type": "int", "min": 1, "max": 20,
     "default": 3},
    {"category": "Process", "label": "Offset", "id": "offset", "type": "int", "default": -2},
    {"category": "Process", "label": "Verify placement", "id": "verify_placement", "type": "bool", "default": True},
    {"category": "Motion", "label": "Gripper type", "id": "gripper_type", "type": "enum",
     "options": ["parallel", "vacuum", "magnetic"], "default": "parallel"},
    {"category": "Process", "label": "Recipe name", "id": "recipe_name", "type": "string", "max_length": 64,
     "default": "Demo bracket"},
]


def cell(items: list | None = None, csv: str = "parameters.csv") -> dict:
    return {"parameters": {"csv": csv, "items": copy.deepcopy(ITEMS if items is None else items)}}


def defs() -> dict[str, ParamDef]:
    return parse_parameters(cell()).by_id()


def store(tmp_path: Path, **kw) -> ParameterStore:
    config = parse_parameters(cell())
    s = ParameterStore(config, str(tmp_path / config.csv), **kw)
    s.start()
    return s


def refused(pid: str, text: str) -> str:
    with pytest.raises(InvalidValue) as e:
        canonical(defs()[pid], text)
    check_said(e.value.said)   # the app can say it in every language
    return str(e.value)


# ---------------------------------------------------------------------------------------------- validation by type
def test_int_accepts_whole_numbers_in_range_and_normalises() -> None:
    d = defs()
    assert canonical(d["parts_per_cycle"], "12") == ("12", 12)
    assert canonical(d["parts_per_cycle"], " +07 ") == ("7", 7)
    assert canonical(d["offset"], "-2000") == ("-2000", -2000)
    assert refused("parts_per_cycle", "2.5") == "Parts per cycle: '2.5' is not a whole number"
    assert refused("parts_per_cycle", "abc") == "Parts per cycle: 'abc' is not a whole number"
    assert refused("parts_per_cycle", "1_0") == "Parts per cycle: '1_0' is not a whole number"
    assert refused("parts_per_cycle", "٣") == "Parts per cycle: '٣' is not a whole number"  # not an ASCII digit
    assert refused("parts_per_cycle", "") == "Parts per cycle: a value is needed"
    assert refused("parts_per_cycle", "25") == "Parts per cycle: 25 is above the maximum 20"
    assert refused("parts_per_cycle", "0") == "Parts per cycle: 0 is below the minimum 1"
    assert refused("offset", str(2 ** 53)).startswith("Offset: 9007199254740992 is too large")


def test_float_keeps_the_text_as_written_and_checks_range_with_unit() -> None:
    d = defs()
    assert canonical(d["approach_height"], "60") == ("60", 60.0)
    assert canonical(d["approach_height"], " +60.25 ") == ("60.25", 60.25)
    assert canonical(d["tolerance"], "1e-05") == ("1e-05", 1e-05)
    assert canonical(d["tolerance"], "0.1") == ("0.1", 0.1)
    assert canonical(d["tolerance"], ".5") == (".5", 0.5)
    assert refused("approach_height", "250") == "Approach height: 250 mm is above the maximum 200 mm"
    assert refused("approach_height", "4.5") == "Approach height: 4.5 mm is below the minimum 5 mm"
    assert refused("approach_height", "abc") == "Approach height: 'abc' is not a number"
    assert refused("approach_height", "12,5") == "Approach height: '12,5' is not a number"
    for bad in ("nan", "inf", "-Infinity", "1_000", "0x10", "1e", "--1"):
        assert refused("tolerance", bad) == f"Tolerance: {bad!r} is not a number"
    assert refused("tolerance", "1e999") == "Tolerance: 1e999 is too large"
    assert refused("speed_factor", "1.5") == "Speed factor: 1.5 is above the maximum 1"  # no unit, no blank
    assert refused("tolerance", "1" * 41).startswith("Tolerance: '1111")


def test_float_decimals() -> None:
    d = defs()
    assert canonical(d["speed_factor"], "0.25")[0] == "0.25"
    assert canonical(d["speed_factor"], "0.250")[0] == "0.250"  # trailing zeros are not decimals
    assert refused("speed_factor", "0.125") == "Speed factor: 0.125 has more than 2 decimals"
    assert refused("speed_factor", "1e-3") == "Speed factor: 1e-3 has more than 2 decimals"
    one = ParamDef("x", "C", "X", "float", "1", decimals=1)
    zero = ParamDef("x", "C", "X", "float", "1", decimals=0)
    with pytest.raises(InvalidValue, match="X: 1.25 has more than 1 decimal$"):
        canonical(one, "1.25")
    with pytest.raises(InvalidValue, match="X: 1.5 must have no decimals"):
        canonical(zero, "1.5")


def test_bool_is_true_or_false_only() -> None:
    d = defs()["verify_placement"]
    assert canonical(d, "true") == ("true", True)
    assert canonical(d, "FALSE") == ("false", False)  # a spreadsheet writes TRUE/FALSE
    for bad in ("yes", "1", "0", "on"):
        assert refused("verify_placement", bad) == f"Verify placement: {bad!r} is not true or false"


def test_enum_only_its_options() -> None:
    d = defs()["gripper_type"]
    assert canonical(d, "vacuum") == ("vacuum", "vacuum")
    assert refused("gripper_type", "suction") == "Gripper type: 'suction' is not one of parallel, vacuum, magnetic"
    assert refused("gripper_type", "Vacuum").startswith("Gripper type: 'Vacuum' is not one of")


def test_string_exact_without_control_characters_within_the_bound() -> None:
    d = defs()["recipe_name"]
    for text in ("", "  padded  ", 'a, "quoted", b', "two\nlines", "tab\there", "Bügel ✓ 部品"):
        assert canonical(d, text) == (text, text)
    assert refused("recipe_name", "bell\x07") == "Recipe name: contains a control character (U+0007)"
    assert refused("recipe_name", "nul\x00") == "Recipe name: contains a control character (U+0000)"
    assert refused("recipe_name", "cr\r\n") == "Recipe name: contains a control character (U+000D)"
    assert refused("recipe_name", "x" * 65) == "Recipe name: 65 characters, at most 64"
    assert canonical(d, "x" * 64)[0] == "x" * 64


# ---------------------------------------------------------------------------------------------- the cell-file section
def test_demo_cell_section() -> None:
    config = parse_parameters(yaml.safe_load(DEMO.read_text()))
    by_id = config.by_id()
    assert config.csv == "parameters.csv"
    assert {d.type for d in config.items} == {"int", "float", "bool", "enum", "string"}
    assert by_id["gripper_type"].options and by_id["gripper_type"].default in by_id["gripper_type"].options
    assert by_id["approach_height"].default == "100" and by_id["verify_placement"].default == "true"
    assert parse_parameters({}) is None
    assert read_values({"cell": {}}) == {}


def test_float_defaults_as_people_write_them() -> None:
    d = defs()
    assert (d["approach_height"].default, d["speed_factor"].default, d["tolerance"].default) == ("50", "0.5", "1e-05")


def test_a_label_or_category_per_language_is_known_to_the_node_by_its_english() -> None:
    c = cell()
    c["parameters"]["items"][0].update(label={"en": "Speed", "es": "Velocidad"}, category={"en": "Motion", "fi": "Liike"})
    d = parse_parameters(c).items[0]
    assert (d.label, d.category) == ("Speed", "Motion")


@pytest.mark.parametrize("change, message", [
    (lambda c: c["parameters"]["items"].append(dict(ITEMS[0])), r"items\[8\]\.id: 'approach_height' is already the id of items\[0\]"),
    (lambda c: c["parameters"]["items"][0].update(default=250), r"items\[0\]\.default: Approach height: 250 mm is above the maximum 200 mm"),
    (lambda c: c["parameters"]["items"][0].update(min=300), r"items\[0\]\.min: 300 is above max 200"),
    (lambda c: c["parameters"]["items"][3].update(default=2.5), r"items\[3\]\.default: expected a whole number"),
    (lambda c: c["parameters"]["items"][5].update(default="yes"), r"items\[5\]\.default: expected true or false"),
    (lambda c: c["parameters"]["items"][5].update(min=0), r"items\[5\]\.min: only int and float parameters have limits"),
    (lambda c: c["parameters"]["items"][6].update(default="suction"), r"items\[6\]\.default: Gripper type: 'suction' is not one of"),
    (lambda c: c["parameters"]["items"][6].pop("options"), r"items\[6\]\.options: an enum needs a non-empty list"),
    (lambda c: c["parameters"]["items"][6].update(options=[1, 2]), r"items\[6\]\.options\[0\]: expected a non-empty string"),
    (lambda c: c["parameters"]["items"][6].update(options=["a", "a"]), r"items\[6\]\.options: listed twice: a"),
    (lambda c: c["parameters"]["items"][7].update(default="x" * 65), r"items\[7\]\.default: Recipe name: 65 characters"),
    (lambda c: c["parameters"]["items"][1].update(decimals=0), r"items\[1\]\.default: Speed factor: 0.5 must have no decimals"),
    (lambda c: c["parameters"]["items"][3].update(decimals=1), r"items\[3\]\.decimals: only float parameters"),
    (lambda c: c["parameters"]["items"][0].pop("default"), r"items\[0\]\.default: missing"),
    (lambda c: c["parameters"]["items"][0].update(type="double"), r"items\[0\]\.type: expected one of int, float"),
    (lambda c: c["parameters"]["items"][0].update(id="Bad Id"), r"items\[0\]\.id: expected lower-case"),
    (lambda c: c["parameters"].update(csv="../escape.csv"), r"parameters\.csv: must be a file path inside DATA_DIR"),
    (lambda c: c["parameters"].update(csv="/etc/passwd"), r"parameters\.csv: must be a file path inside DATA_DIR"),
    (lambda c: c["parameters"]["items"][0].update(label={"es": "Velocidad"}), r"items\[0\]\.label\.en: expected a non-empty"),
])
def test_section_errors_name_the_field(change, message: str) -> None:
    c = cell()
    change(c)
    with pytest.raises(ConfigError, match=message):
        parse_parameters(c)


# ---------------------------------------------------------------------------------------------- the CSV
TRICKY = {
    "approach_height": "60.5", "speed_factor": "0.1", "tolerance": "1e-05", "parts_per_cycle": "12",
    "offset": "-7", "verify_placement": "false", "gripper_type": "vacuum",
    "recipe_name": 'Bügel, "links"\nzweite Zeile\t✓ 部品',
}


def test_round_trip_is_exact_for_every_type(tmp_path: Path) -> None:
    config = parse_parameters(cell())
    path = tmp_path / "p.csv"
    write_csv(str(path), render(config.items, TRICKY))
    result = read_csv(str(path), config.items, "p.csv")
    assert result.problems == [] and result.texts == TRICKY
    text = path.read_text(encoding="utf-8")
    assert text.splitlines()[0] == ",".join(COLUMNS)
    assert "approach_height,60.5,mm,Motion,Approach height\n" in text
    assert 'recipe_name,"Bügel, ""links""\nzweite Zeile\t✓ 部品",,Process,Recipe name\n' in text
    assert "\r" not in text
    values = read_values(cell(csv="p.csv"), str(tmp_path))
    assert values == {"approach_height": 60.5, "speed_factor": 0.1, "tolerance": 1e-05, "parts_per_cycle": 12,
                      "offset": -7, "verify_placement": False, "gripper_type": "vacuum",
                      "recipe_name": TRICKY["recipe_name"]}
    assert type(values["parts_per_cycle"]) is int and type(values["approach_height"]) is float


def test_missing_file_is_created_from_the_defaults(tmp_path: Path) -> None:
    s = store(tmp_path / "sub")  # the directory is created too
    path = tmp_path / "sub" / "parameters.csv"
    assert path.exists() and s.problems == []
    assert read_csv(str(path), s.defs, "x").texts == {d.id: d.default for d in s.defs}
    assert s.message == ""
    assert oct(path.stat().st_mode & 0o777) == oct(0o644)


def test_invalid_values_and_unknown_ids_are_reported_and_defaults_used(tmp_path: Path) -> None:
    path = tmp_path / "parameters.csv"
    path.write_text("\ufeffId , Value,unit\n"                 # spreadsheet BOM, other header spelling
                    "approach_height,250,mm\n"                # out of range
                    "parts_per_cycle, 4 \n"                   # padded: fine
                    "ghost,1\n"                               # unknown id
                    "\n"                                       # blank line: nothing
                    "gripper_type,suction\n"                  # not an option
                    "verify_placement,TRUE\n"                 # a spreadsheet's bool: fine
                    "parts_per_cycle,5\n"                     # twice
                    "offset\n"                                # no value column
                    ",3\n", encoding="utf-8")                 # no id
    s = store(tmp_path)
    assert s.texts["approach_height"] == "50" and s.texts["parts_per_cycle"] == "4"
    assert s.texts["gripper_type"] == "parallel" and s.texts["verify_placement"] == "true"
    assert s.problems == [
        "line 2: Approach height: 250 mm is above the maximum 200 mm; default 50 mm used",
        "line 4: unknown parameter 'ghost'; ignored",
        "line 6: Gripper type: 'suction' is not one of parallel, vacuum, magnetic; default 'parallel' used",
        "line 8: parts_per_cycle again (first on line 3); ignored",
        "line 9: Offset: no value; default -2 used",
        "line 10: no id; ignored",
        "Speed factor (speed_factor) is not in parameters.csv; default 0.5 used",
        "Tolerance (tolerance) is not in parameters.csv; default 1e-05 m used",
        "Recipe name (recipe_name) is not in parameters.csv; default 'Demo bracket' used",
    ]
    assert s.message.startswith("9 problems in parameters.csv: line 2: Approach height")
    assert path.read_text(encoding="utf-8").startswith("\ufeffId , Value")  # not rewritten at start
    # Said with codes (issue 29): the Parameters page says the file's problems in the user's language, each nested.
    assert [p.code for p in s.problems] == ["parameters.line_invalid", "parameters.line_unknown",
                                            "parameters.line_invalid", "parameters.line_again",
                                            "parameters.line_no_value", "parameters.line_no_id",
                                            *["parameters.not_in_file"] * 3]
    assert dict(s.problems[0].params)["why.code"] == "parameters.above_max"
    assert dict(s.problems[0].params)["default.code"] == "parameters.quantity"
    assert s.message.code == "parameters.file_problems"
    for text in [*s.problems, s.message]:
        check_said(text)


def test_multi_line_values_are_numbered_by_their_first_line(tmp_path: Path) -> None:
    path = tmp_path / "parameters.csv"
    path.write_text('id,value\nrecipe_name,"a\nb\nc"\nparts_per_cycle,99\n', encoding="utf-8")
    s = store(tmp_path)
    assert s.texts["recipe_name"] == "a\nb\nc"
    assert s.problems[0] == "line 5: Parts per cycle: 99 is above the maximum 20; default 3 used"


@pytest.mark.parametrize("content, problem", [
    (b"", "parameters.csv is empty: every default used"),
    (b"\n\n", "parameters.csv is empty: every default used"),
    (b"name;wert\nx;1\n", "parameters.csv has no header line with `id` and `value` columns: every default used"),
    (b"id,value\n\xff\xfe\x00garbage", "cannot read parameters.csv: 'utf-8' codec can't decode"),
    (b"id,value\n" + b"x" * (csvfile.MAX_FILE_BYTES + 1), "parameters.csv is larger than"),
])
def test_corrupt_files_never_crash(tmp_path: Path, content: bytes, problem: str) -> None:
    (tmp_path / "parameters.csv").write_bytes(content)
    s = store(tmp_path)
    assert s.texts == {d.id: d.default for d in s.defs}
    assert len(s.problems) == 1 and s.problems[0].startswith(problem), s.problems
    check_said(s.message)   # "1 problem in …", the problem nested
    assert (tmp_path / "parameters.csv").read_bytes() == content  # kept for a person to look at


def test_a_nul_byte_is_an_invalid_value(tmp_path: Path) -> None:
    (tmp_path / "parameters.csv").write_bytes(b"id,value\nrecipe_name,a\x00b\n")
    s = store(tmp_path)
    assert s.texts["recipe_name"] == "Demo bracket"
    assert s.problems[0] == ("line 2: Recipe name: contains a control character (U+0000); "
                             "default 'Demo bracket' used")


def test_unreadable_file(tmp_path: Path) -> None:
    (tmp_path / "parameters.csv").mkdir()  # a directory where the file should be
    s = store(tmp_path)
    assert s.problems and s.problems[0].startswith("cannot read parameters.csv: Is a directory")
    result = s.set([("parts_per_cycle", "4")])
    assert not result.success and result.message.startswith("could not save parameters.csv")


# ---------------------------------------------------------------------------------------------- set
def test_set_saves_only_differences_and_says_how_many(tmp_path: Path) -> None:
    s = store(tmp_path)
    result = s.set([("approach_height", "60"), ("recipe_name", 'a, "b"'), ("parts_per_cycle", "3"),
                    ("speed_factor", "0.50")])  # equal to the value in use: not changes
    assert result.success and result.message == "saved 2 parameters" and result.errors == ()
    assert result.changed == (("approach_height", "50", "60"), ("recipe_name", "Demo bracket", 'a, "b"'))
    assert s.texts["speed_factor"] == "0.5"
    assert read_values(cell(), str(tmp_path))["recipe_name"] == 'a, "b"'
    assert s.set([("approach_height", "60.0")]).message == "nothing to save: no value differs from the saved one"
    assert s.set([]).success
    one = s.set([("verify_placement", "false")])
    assert one.message == "saved 1 parameter"


def test_set_is_all_or_nothing_and_lists_every_bad_field(tmp_path: Path) -> None:
    s = store(tmp_path)
    path = tmp_path / "parameters.csv"
    before = path.read_bytes()
    result = s.set([("approach_height", "60"), ("parts_per_cycle", "2.5"), ("ghost", "1"),
                    ("approach_height", "70"), ("gripper_type", "suction")])
    assert not result.success
    assert result.errors == (
        ("parts_per_cycle", "Parts per cycle: '2.5' is not a whole number"),
        ("ghost", "unknown parameter 'ghost'"),
        ("approach_height", "Approach height: changed twice in one request"),
        ("gripper_type", "Gripper type: 'suction' is not one of parallel, vacuum, magnetic"),
    )
    assert result.message.startswith("nothing saved: 4 invalid values: Parts per cycle: '2.5' is not a whole number;")
    assert path.read_bytes() == before and not (tmp_path / "parameters.csv.bak").exists()
    assert s.texts["approach_height"] == "50"
    one = s.set([("approach_height", "250"), ("parts_per_cycle", "4")])
    assert one.message == "nothing saved: 1 invalid value: Approach height: 250 mm is above the maximum 200 mm"
    assert one.errors == (("approach_height", "Approach height: 250 mm is above the maximum 200 mm"),)
    many = s.set([("ghost", "1")] * 200)
    assert not many.success and many.message.startswith("too many changes in one request (200, at most 100)")


def test_what_set_says_has_codes_the_app_can_say_nested_to_each_field(tmp_path: Path) -> None:
    """Every answer of set, and every field's error, is said with a code (issue 29): the app says the whole text in
    the user's language, each listed field's error included, with the numbers and units as parameters."""
    s = store(tmp_path)
    refused = s.set([("parts_per_cycle", "2.5"), ("ghost", "1"), ("approach_height", "250"), ("speed_factor", "1.5")])
    assert refused.message.code == "parameters.nothing_saved"
    params = dict(refused.message.params)
    assert params["count"] == "4" and params["errors.code"] == "parameters.list"
    assert params["errors.first.code"] == "parameters.not_whole"
    assert params["errors.rest.rest.first.code"] == "parameters.above_max"
    assert params["errors.rest.rest.first.value.code"] == "parameters.quantity"
    assert params["errors.rest.rest.first.value.number"] == "250"
    assert params["errors.rest.rest.first.max.unit"] == "mm"
    assert params["errors.rest.rest.rest.value"] == "1.5"            # no unit: the number alone
    assert [m.code for _, m in refused.errors] == [
        "parameters.not_whole", "parameters.unknown", "parameters.above_max", "parameters.above_max"]
    said = [refused.message, *(m for _, m in refused.errors)]
    said.append(s.set([("approach_height", "250")]).message)
    said.append(s.set([("ghost", "1")] * 200).message)
    said.append(s.set([("approach_height", "50")]).message)
    said.append(s.set([("approach_height", "60")]).message)
    said.append(s.set([("approach_height", "61"), ("parts_per_cycle", "4")]).message)
    assert [m.code for m in said[-5:]] == ["parameters.nothing_saved_one", "parameters.too_many_changes",
                                           "parameters.nothing_to_save", "parameters.saved_one", "parameters.saved"]
    for text in said:
        check_said(text)


def test_a_file_of_many_bad_lines_gives_a_short_message_and_every_problem(tmp_path: Path) -> None:
    """The message lists ten problems and says how many more (it nests once per problem: 2000 would make megabytes
    of parameters); `problems` (the node logs each) keeps them all."""
    rows = "".join(f"ghost{i},1\n" for i in range(2000))
    (tmp_path / "parameters.csv").write_text("id,value\n" + rows, encoding="utf-8")
    s = store(tmp_path)
    assert len(s.problems) == 2000 + len(s.defs)
    assert s.message.endswith(f"; and {len(s.problems) - 10} more")
    assert len(s.message.params) < 100 and len(s.message) < 1000
    check_said(s.message)


def test_set_backs_up_and_rotates(tmp_path: Path) -> None:
    s = store(tmp_path)
    path = tmp_path / "parameters.csv"
    contents = [path.read_text()]
    for n in ("4", "5", "6", "7"):
        assert s.set([("parts_per_cycle", n)]).success
        contents.append(path.read_text())
    assert (tmp_path / "parameters.csv.bak").read_text() == contents[3]
    assert (tmp_path / "parameters.csv.bak.1").read_text() == contents[2]
    assert (tmp_path / "parameters.csv.bak.2").read_text() == contents[1]
    assert not (tmp_path / "parameters.csv.bak.3").exists()
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")) == []


def test_start_removes_the_temp_files_of_an_interrupted_save(tmp_path: Path) -> None:
    """A crash mid-save leaves a temp file (test_power_loss.py); the next start removes it and only it."""
    left = [".parameters.csv.k2j4x_9a.tmp", ".parameters.csv.bak.1.p0q8zz1e.tmp"]
    kept = [".~lock.parameters.csv#", ".other.csv.k2j4x_9a.tmp", "parameters.csv.tmp"]
    for name in left + kept:
        (tmp_path / name).write_text("id,value\n")
    config = parse_parameters(cell())
    s = ParameterStore(config, str(tmp_path / config.csv))
    assert s.start() == ["removed 2 temp files of an interrupted save of parameters.csv",
                         "parameters.csv did not exist: created from the defaults"]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(kept + ["parameters.csv"])
    assert s.problems == []


def test_a_failing_write_leaves_the_old_file_intact(tmp_path: Path, monkeypatch) -> None:
    s = store(tmp_path)
    assert s.set([("parts_per_cycle", "4")]).success
    path = tmp_path / "parameters.csv"
    before = path.read_bytes()

    def half_then_disk_full(fd: int, data: bytes) -> None:
        os.write(fd, data[: len(data) // 2])
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(csvfile, "_write_all", half_then_disk_full)
    result = s.set([("parts_per_cycle", "9"), ("recipe_name", "new")])
    assert not result.success
    assert result.message == "could not save parameters.csv: No space left on device; nothing saved"
    assert path.read_bytes() == before
    assert s.texts["parts_per_cycle"] == "4" and s.texts["recipe_name"] == "Demo bracket"
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []  # no temp file left
    monkeypatch.undo()
    assert s.set([("parts_per_cycle", "9")]).success


def test_a_failing_rename_leaves_the_old_file_intact(tmp_path: Path, monkeypatch) -> None:
    s = store(tmp_path, backups=0)
    path = tmp_path / "parameters.csv"
    before = path.read_bytes()

    def refuse(src: str, dst: str) -> None:
        raise OSError(errno.EACCES, os.strerror(errno.EACCES))

    monkeypatch.setattr(csvfile.os, "replace", refuse)
    assert s.set([("parts_per_cycle", "9")]).message == "could not save parameters.csv: Permission denied; nothing saved"
    monkeypatch.undo()
    assert path.read_bytes() == before and not (tmp_path / "parameters.csv.bak").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["parameters.csv"]


def test_set_rewrites_a_corrupt_file_after_backing_it_up(tmp_path: Path) -> None:
    path = tmp_path / "parameters.csv"
    path.write_text("id,value\nghost,1\napproach_height,abc\n")
    s = store(tmp_path)
    assert len(s.problems) == 9  # ghost, abc, and 7 parameters not in the file
    assert s.set([("parts_per_cycle", "4")]).success
    assert s.problems == [] and s.message == ""
    assert (tmp_path / "parameters.csv.bak").read_text() == "id,value\nghost,1\napproach_height,abc\n"
    assert read_parameters(cell(), str(tmp_path)).problems == []


def test_hand_edits_are_picked_up_and_a_deleted_file_is_written_again(tmp_path: Path) -> None:
    s = store(tmp_path)
    assert s.refresh() == (False, [])
    assert s.set([("parts_per_cycle", "4")]).success
    path = tmp_path / "parameters.csv"
    path.write_text(path.read_text().replace("parts_per_cycle,4", "parts_per_cycle,6") + "ghost,1\n")
    changed, notes = s.refresh()
    assert changed and s.texts["parts_per_cycle"] == "6" and s.problems == ["line 10: unknown parameter 'ghost'; ignored"]
    assert s.refresh() == (False, [])
    # a set after a hand edit keeps the edit
    assert s.set([("approach_height", "70")]).success
    assert read_values(cell(), str(tmp_path))["parts_per_cycle"] == 6
    path.unlink()
    changed, notes = s.refresh()
    assert not changed and notes == ["parameters.csv did not exist: created from the values in use"]
    assert read_values(cell(), str(tmp_path))["approach_height"] == 70.0


# ---------------------------------------------------------------------------------------------- the reader
def test_reader_defaults_for_missing_file_and_invalid_values(tmp_path: Path, monkeypatch) -> None:
    snap = read_parameters(cell(), str(tmp_path))
    assert snap.problems == ["parameters.csv does not exist: every default used"]
    assert snap.values["approach_height"] == 50 and snap.values["verify_placement"] is True
    assert not (tmp_path / "parameters.csv").exists()  # the reader never writes
    (tmp_path / "parameters.csv").write_text("id,value\nparts_per_cycle,x\noffset,5\n")
    monkeypatch.setenv("DATA_DIR", str(tmp_path))
    values = read_values(cell())
    assert values["parts_per_cycle"] == 3 and values["offset"] == 5
    assert read_parameters(cell()).path == str(tmp_path / "parameters.csv")
