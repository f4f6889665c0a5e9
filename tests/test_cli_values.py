"""Comma-separated option values (bladelab.cli.values)."""

import pytest

from bladelab.cli.values import parse_list
from bladelab.errors import SpecError


def test_a_list_is_read_with_its_conversion_and_empty_items_skipped():
    assert parse_list("1, 2,,3", "--seeds", int) == [1, 2, 3]
    assert parse_list("Cat4,Cat6", "--categories") == ["Cat4", "Cat6"]


def test_errors_name_the_option_and_give_the_hint():
    with pytest.raises(SpecError, match="cannot read --speeds 'a,b'") as err:
        parse_list("a,b", "--speeds", float, hint="speeds in m/s")
    assert err.value.where == "--speeds" and err.value.hint == "speeds in m/s"
    with pytest.raises(SpecError, match="no --categories given"):
        parse_list(" , ", "--categories")
