"""The one formatter of numbers shown (issue #27, item 7): what it writes reads back as the number
it rounded to, a negative number carries a true minus sign, and signed numbers never read −0."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from core.numbers import (
    MINUS,
    format_change,
    format_number,
    format_signed,
    format_signed_number,
    parse_number,
    rounded,
)

finite = st.floats(min_value=-1e300, max_value=1e300, allow_nan=False, allow_infinity=False).filter(
    lambda v: v == 0 or abs(v) > 1e-300)


@given(finite, st.integers(min_value=1, max_value=15))
def test_a_number_written_reads_back_as_its_rounding(value, digits):
    text = format_number(value, digits)
    assert "-" not in text.split("×")[0]  # the mantissa's sign is a true minus sign
    assert text.startswith(MINUS) == (rounded(value, digits) < 0)
    assert parse_number(text) == pytest.approx(rounded(value, digits), rel=1e-12, abs=0)


@given(finite, st.integers(min_value=1, max_value=6))
def test_a_signed_number_has_its_sign_and_never_a_signed_zero(value, digits):
    text = format_signed_number(value, digits)
    shown = parse_number(text.removeprefix("+"))
    if shown == 0:
        assert text == "0"
    else:
        assert text[0] == ("+" if value > 0 else MINUS)
        assert shown == pytest.approx(rounded(value, digits), rel=1e-12)


@pytest.mark.parametrize(("value", "text"), [(-0.004, "0.00"), (0.004, "0.00"), (-0.41, "−0.41"), (0.005001, "+0.01")])
def test_signed_decimals(value, text):
    assert format_signed(value, 2) == text


def test_a_change_is_a_signed_percentage():
    assert format_change(-0.0358) == "−3.58 %"
    assert format_change(0.05) == "+5 %"
    assert format_change(1e-7) == "0 %"
    assert format_signed(math.nan) == format_signed_number(math.inf) == format_number(None) == "–"
