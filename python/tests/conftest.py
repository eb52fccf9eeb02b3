"""Every test of the package runs with Vulkan validation on, and fails on any message it reports.

tools/test.sh sets RANGESYNTH_VALIDATION=1, which each renderer and verifier the package makes
reads; `rangesynth.validation_messages()` collects what validation reported on all of them.
"""

import os

import pytest

import rangesynth


@pytest.fixture(autouse=True)
def no_validation_messages():
    assert os.environ.get("RANGESYNTH_VALIDATION") == "1", "tools/test.sh turns validation on"
    # What validation reported between tests (a renderer an earlier test left to the garbage
    # collector, torn down since) fails this one, naming it as earlier.
    earlier = rangesynth.validation_messages()
    assert not earlier, "Vulkan validation reported after an earlier test:\n" + "\n".join(earlier)
    yield
    messages = rangesynth.validation_messages()
    assert not messages, "Vulkan validation reported:\n" + "\n".join(messages)
