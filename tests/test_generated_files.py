"""The generated-file comparison: numbers at the written precision, named differences."""

from __future__ import annotations

from treeimpact.analytic.engine.generated_files import (
    URDF_DIGITS,
    file_differences,
    fixed_digits,
    fixed_precision_xml,
    xml_differences,
)

URDF = '<robot name="r"><link name="l"><inertia ixx="{0}" iyy="{1}" izz="0"/></link></robot>'


def test_fixed_digits_writes_twelve_significant_digits_and_no_negative_zero():
    assert fixed_digits(0.0006196908509851375) == "0.000619690850985"
    assert fixed_digits(0.0006196908509851374) == "0.000619690850985"
    assert fixed_digits(-0.0) == "0"
    assert float(fixed_digits(1.0 / 3.0)) == 0.333333333333


def test_last_bits_of_a_float_are_no_difference():
    """The failure of a fresh install: the 16th significant digit moved."""
    a = URDF.format(repr(0.0006196908509851375), "1.5")
    b = URDF.format(repr(0.0006196908509851374), "1.5")
    assert a != b
    assert xml_differences(a, b, URDF_DIGITS) == []


def test_one_unit_in_the_last_written_digit_is_no_difference_but_two_are():
    a = URDF.format("0.000619690850985", "1.5")
    assert xml_differences(a, URDF.format("0.000619690850986", "1.5"), URDF_DIGITS) == []
    diff = xml_differences(a, URDF.format("0.000619690850988", "1.5"), URDF_DIGITS)
    assert diff == ["/robot[@name='r']/link[@name='l']/inertia: ixx "
                    "'0.000619690850985' != '0.000619690850988'"]


def test_element_attribute_and_word_differences_are_named():
    a = URDF.format("1", "2")
    assert xml_differences(a, a.replace('izz="0"', ""), URDF_DIGITS) == [
        "/robot[@name='r']/link[@name='l']/inertia: izz '0' != None"]
    assert xml_differences(a, a.replace("inertia", "mass"), URDF_DIGITS)[0].endswith(
        "element 'inertia' != 'mass'")
    assert xml_differences(a, a.replace('name="l"', 'name="k"'), URDF_DIGITS)
    assert xml_differences(a, "<robot", URDF_DIGITS)[0].startswith("not parseable XML")


def test_file_differences_names_missing_and_changed_files(tmp_path):
    (tmp_path / "same.urdf").write_text(URDF.format("1", "2"))
    (tmp_path / "changed.urdf").write_text(URDF.format("1", "2"))
    files = {"same.urdf": URDF.format("1", "2"), "changed.urdf": URDF.format("1", "3"),
             "new.urdf": URDF.format("1", "2")}
    diff = file_differences(tmp_path, files, URDF_DIGITS)
    assert set(diff) == {"changed.urdf", "new.urdf"}
    assert diff["new.urdf"] == ["missing"]
    assert "iyy '2' != '3'" in diff["changed.urdf"][0]


def test_written_files_do_not_change_with_the_last_bits():
    """The rounding the writer applies makes the text itself platform-stable."""
    a = URDF.format(repr(0.0006196908509851375), "1.0")
    b = URDF.format(repr(0.0006196908509851374), "1.0")
    assert fixed_precision_xml(a, URDF_DIGITS) == fixed_precision_xml(b, URDF_DIGITS)
    assert 'ixx="0.000619690850985" iyy="1" izz="0"' in fixed_precision_xml(a, URDF_DIGITS)
