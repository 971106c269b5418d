"""One-line errors: a long value is cut, a path never (the user must see which file)."""

from pathlib import Path

from regrasp.core.exceptions import InvalidParameterError, short_repr


def test_a_long_number_is_cut_but_a_long_path_is_shown_whole():
    assert len(short_repr(10 ** 400)) == 80 and short_repr(10 ** 400).endswith("...")
    deep = Path("/tmp") / "/".join(f"folder{i:03d}" for i in range(40)) / "figures"
    for value in (deep, str(deep)):
        message = str(InvalidParameterError("--plot", value, "a directory that can be written"))
        assert str(deep) in message and "\n" not in message
