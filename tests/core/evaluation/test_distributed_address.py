"""A malformed Dask scheduler address (ursim_core.evaluation.distributed.connect) is a ParameterError
saying so, as an unreachable one is, never a traceback (``ursim evaluate``, ``ursim match-batch``)."""

from __future__ import annotations

import pytest

pytest.importorskip("distributed", reason="the 'distributed' extra (dask[distributed]) is not installed")

from ursim_core.errors import ParameterError
from ursim_core.evaluation.distributed import connect


@pytest.mark.parametrize("address", ["not a url", "http://x:y", "", "tcp://", "tcp://host:port"])
def test_a_malformed_address_is_a_parameter_error_naming_it(address):
    with pytest.raises(ParameterError, match="is not a Dask scheduler address") as caught:
        connect(address)
    assert repr(address) in str(caught.value) and caught.value.field == "scheduler"
    assert "\n" not in str(caught.value)


def test_no_client_is_started_for_a_malformed_address(monkeypatch):
    # A Client that fails to start is left half made; its clean-up can deadlock the next one.
    import distributed

    class NoClient:
        def __init__(self, *args, **kwargs):
            raise AssertionError("a Client was started")

    monkeypatch.setattr(distributed, "Client", NoClient)
    for address in ("not a url", "http://x:y"):
        with pytest.raises(ParameterError, match="is not a Dask scheduler address"):
            connect(address)
