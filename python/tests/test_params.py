"""binbow.LoopDetectorParams: every field, checked as parameter files are."""
import copy
import json
import pickle

import numpy as np
import pytest

import binbow

P = binbow.LoopDetectorParams


def test_every_field_of_the_library_is_a_property():
    library = json.loads(P().to_json())  # the library's own table of fields
    assert list(P().to_dict()) == list(library)
    assert P().to_dict() == library
    for name, value in library.items():
        assert getattr(P(), name) == value
        assert type(getattr(P(), name)) is type(value), name
        assert getattr(P, name).__doc__, f"{name} has no docstring"


def test_keywords_and_properties():
    params = P(alpha=0.5, k=2, geometric_check="exhaustive", accept_single_candidate=True)
    assert (params.alpha, params.k, params.geometric_check) == (0.5, 2, "exhaustive")
    assert params.accept_single_candidate is True
    params.dislocal = 7
    params.geometric_check = "direct_index"  # '_' for '-' as in files
    params.max_neighbor_ratio = np.float32(0.5)
    params.min_inliers = np.int64(20)
    assert (params.dislocal, params.geometric_check, params.min_inliers) == (7, "direct-index", 20)
    assert params.max_neighbor_ratio == 0.5


def test_frequency_scales_frame_counts_as_files_do(tmp_path):
    scaled = P.for_frequency(10)
    assert (scaled.frequency, scaled.dislocal, scaled.max_db_results) == (10.0, 200, 500)
    assert P(frequency=10) == scaled
    assert P(frequency=10, dislocal=5).dislocal == 5
    assert P.from_dict({"frequency": 10}) == scaled
    (tmp_path / "p.json").write_text('{"frequency": 10}')
    assert P.from_file(tmp_path / "p.json") == scaled
    # The property alone rescales nothing: it sets one field.
    params = P()
    params.frequency = 10
    assert (params.frequency, params.dislocal) == (10.0, 20)


def test_files_json_and_dict_round_trips(tmp_path):
    params = P(alpha=0.2, k=1, geometric_check="none", ransac_confidence=0.995)
    assert P.from_dict(params.to_dict()) == params
    assert P.from_json(params.to_json()) == params
    (tmp_path / "p.json").write_text(params.to_json())
    assert P.from_file(str(tmp_path / "p.json")) == params
    (tmp_path / "p.yml").write_text("%YAML:1.0\nalpha: 0.2\nk: 1\n")
    assert P.from_file(tmp_path / "p.yml") == P(alpha=0.2, k=1)
    (tmp_path / "k.json").write_text('{"k": 5}')
    assert P.from_file(tmp_path / "k.json", defaults=P(alpha=0.7)) == P(alpha=0.7, k=5)
    assert P(alpha=0.25) != P()


def test_repr_evaluates_to_an_equal_object():
    params = P(frequency=4, alpha=0.125, geometric_check="exhaustive")
    text = repr(params)
    assert text.startswith("binbow.LoopDetectorParams(frequency=4.0, ")
    assert eval(text, {"binbow": binbow}) == params


def test_pickle_and_copy():
    params = P(alpha=0.75, max_verified_entries=3)
    for clone in (pickle.loads(pickle.dumps(params)), copy.copy(params), copy.deepcopy(params)):
        assert clone == params and clone is not params
    clone = copy.copy(params)
    clone.alpha = 0.1
    assert params.alpha == 0.75, "a copy is independent"


def test_invalid_values_are_value_errors_with_the_library_message():
    with pytest.raises(ValueError, match=r"alpha must be in \[0, 1000\], got -1"):
        P(alpha=-1)
    with pytest.raises(ValueError, match="min_inliers must be in"):
        P.from_dict({"min_inliers": 3})
    with pytest.raises(ValueError, match="frequency must be in"):
        P.for_frequency(0)
    with pytest.raises(ValueError, match="must be in"):
        P(alpha=float("nan"))
    with pytest.raises(ValueError, match='unknown geometric check "ransac"'):
        P(geometric_check="ransac")
    with pytest.raises(ValueError, match="out of range"):
        P(k=2**70)
    with pytest.raises(ValueError, match="invalid JSON"):
        P.from_json("{")
    params = P()
    with pytest.raises(ValueError, match="ransac_confidence"):
        params.ransac_confidence = 1.0
    assert params.ransac_confidence == 0.99, "a refused value leaves the field as it was"


def test_wrong_types_and_names_are_type_errors():
    with pytest.raises(TypeError, match="k must be an int, got float"):
        P(k=3.0)
    with pytest.raises(TypeError, match="k must be an int, got bool"):
        P(k=True)
    with pytest.raises(TypeError, match="use_normalised_score must be a bool, got int"):
        P(use_normalised_score=1)
    with pytest.raises(TypeError, match="alpha must be a real number, got str"):
        P(alpha="0.3")
    with pytest.raises(TypeError, match="geometric_check must be a str"):
        P(geometric_check=1)
    with pytest.raises(TypeError, match='unknown loop detector parameter "alhpa"'):
        P(alhpa=0.3)
    with pytest.raises(ValueError, match='unknown loop detector parameter "alhpa"'):
        P.from_dict({"alhpa": 0.3})
    with pytest.raises(TypeError, match="must be an int"):
        P().k = "3"


def test_file_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"alpha": "high"}')
    with pytest.raises(OSError, match="bad.json.*alpha"):
        P.from_file(bad)
    with pytest.raises(OSError, match="missing.json"):
        P.from_file(tmp_path / "missing.json")
