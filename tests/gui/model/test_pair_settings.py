"""Which matching settings belong to which maps (ursim_gui.model.pair_settings), without Qt."""

from __future__ import annotations

from ursim_gui.model.pair_settings import MapIdentities, recorded_settings


def test_the_rules_without_qt():
    identities = MapIdentities({"sketch": None, "metric": "m"})
    assert identities.settings_to_forget("sketch", None) == ()  # the canvas's drawing, edited
    assert identities.settings_to_forget("sketch", "s") == ("orientation", "input_kind", "scale")
    assert identities.settings_to_forget("sketch", "s") == ()
    assert identities.settings_to_forget("metric", "m") == ()
    assert identities.settings_to_forget("metric", None) == ("scale",)
    assert recorded_settings({"config": {"input_kind": "sketch", "scale": 1e9}}) == {
        "input_kind": "sketch",
        "scale": None,
    }
    assert recorded_settings({"config": {"scale": True}}) == {"input_kind": None, "scale": None}
    assert recorded_settings({"config": "x"}) == {} == recorded_settings([1])
