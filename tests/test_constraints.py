"""Constraint files: good ones parse, every bad one is refused with the file and the culprit named."""
import numpy as np
import pytest

from style_coanalysis.constraints import (labels_to_array, read_labels_csv, read_triplets_csv,
                                          triplets_to_array)
from style_coanalysis.meshes import InputError

NAMES = ["Chair.001", "Chair.002", "Table", "Bed", "Stool"]


def _write(tmp_path, text, name="c.csv"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_good_label_file_parses_with_header_comments_and_blanks(tmp_path):
    p = _write(tmp_path, "name,style\n# a comment\n\nChair.001, Ming\nTable,Japanese\n Bed ,Ming\n")
    labels = read_labels_csv(p, NAMES)
    assert labels == {"Chair.001": "Ming", "Table": "Japanese", "Bed": "Ming"}
    y, classes = labels_to_array(labels, NAMES)
    assert classes == ["Japanese", "Ming"]
    np.testing.assert_array_equal(y, [1, -1, 0, 1, -1])
    # header is optional
    assert read_labels_csv(_write(tmp_path, "Chair.001,A\nStool,B\n", "n.csv"), NAMES) == {
        "Chair.001": "A", "Stool": "B"}


def test_unknown_label_names_are_all_listed(tmp_path):
    p = _write(tmp_path, "Chair.001,A\nSofa,B\nLamp,A\nTable,B\n", "mine.csv")
    with pytest.raises(InputError) as err:
        read_labels_csv(p, NAMES)
    msg = str(err.value)
    assert "mine.csv" in msg and "'Sofa'" in msg and "'Lamp'" in msg and "'Table'" not in msg


def test_one_style_is_refused(tmp_path):
    with pytest.raises(InputError, match="two different styles.*'Ming'"):
        read_labels_csv(_write(tmp_path, "Chair.001,Ming\nTable,Ming\n"), NAMES)
    with pytest.raises(InputError, match="two different styles"):
        read_labels_csv(_write(tmp_path, "# nothing\n", "empty.csv"), NAMES)


def test_malformed_and_conflicting_label_rows_give_the_line(tmp_path):
    with pytest.raises(InputError, match=r"c\.csv, line 3"):
        read_labels_csv(_write(tmp_path, "name,style\nChair.001,A\nTable\nBed,B\n"), NAMES)
    with pytest.raises(InputError, match=r"line 2.*'Chair.001'.*'A'.*line 1.*'B'"):
        read_labels_csv(_write(tmp_path, "Chair.001,A\nChair.001,B\nBed,A\n", "d.csv"), NAMES)


def test_good_triplets_parse(tmp_path):
    p = _write(tmp_path, "a,b,c\nChair.001,Chair.002,Table\n\n# x\nBed,Stool,Table\n")
    trips = read_triplets_csv(p, NAMES)
    assert trips == [("Chair.001", "Chair.002", "Table"), ("Bed", "Stool", "Table")]
    np.testing.assert_array_equal(triplets_to_array(trips, NAMES), [[0, 1, 2], [3, 4, 2]])


def test_bad_triplets(tmp_path):
    with pytest.raises(InputError, match=r"t\.csv, line 2.*three different"):
        read_triplets_csv(_write(tmp_path, "Bed,Stool,Table\nBed,Stool,Bed\n", "t.csv"), NAMES)
    with pytest.raises(InputError, match=r"line 1: expected 'a,b,c'"):
        read_triplets_csv(_write(tmp_path, "Bed,Stool\n", "u.csv"), NAMES)
    with pytest.raises(InputError) as err:
        read_triplets_csv(_write(tmp_path, "Bed,Stool,Ghost\nPhantom,Bed,Table\n", "v.csv"), NAMES)
    assert "'Ghost'" in str(err.value) and "'Phantom'" in str(err.value) and "v.csv" in str(err.value)
    text = "Bed,Stool,Table\nBed,Table,Stool\nChair.001,Chair.002,Table\nChair.001,Table,Chair.002\n"
    with pytest.raises(InputError) as err:
        read_triplets_csv(_write(tmp_path, text, "w.csv"), NAMES)
    msg = str(err.value)
    assert "w.csv" in msg and "2 contradictory" in msg
    assert "Bed,Stool,Table" in msg and "Chair.001,Table,Chair.002" in msg
