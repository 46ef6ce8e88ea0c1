"""scoopsim.load_scene and scoopsim.InputError: the validated scene, --set overrides, and bad input
as an exception whose str() is the CLI's one line (oracle: `scoopsim check` on the same input)."""

import subprocess

import pytest

import scoopsim
from conftest import BIN, scene_path


def test_loads_a_scene_and_applies_overrides():
    scene = scoopsim.load_scene(scene_path("tiny_dig.yaml"))
    assert scene.has_dig and not scene.has_arm
    assert scene.bite_depth == 0.02 and scene.bed_material == "snow"
    shallower = scoopsim.load_scene(scene_path("tiny_dig.yaml"),
                                 overrides={"dig.bite_depth": 0.01, "dig.passes": 2})
    assert shallower.bite_depth == 0.01 and shallower.passes == 2
    # The same as a list of KEY=VALUE, as on the command line; kept in the scene's text.
    same = scoopsim.load_scene(scene_path("tiny_dig.yaml"), overrides=["dig.bite_depth=0.01"])
    assert same.bite_depth == 0.01
    assert "# scoopsim --set dig.bite_depth=0.01" in same.yaml_text


def test_bad_value_raises_input_error_carrying_file_line_key():
    with pytest.raises(scoopsim.InputError) as info:
        scoopsim.load_scene(scene_path("tiny_dig.yaml"), overrides={"bed.radius": -1})
    e = info.value
    assert isinstance(e, ValueError)
    assert e.key == "bed.radius"
    assert e.got == "-1"
    assert "bed.radius=-1" in e.file  # an error about an override names the --set
    assert e.expected
    # str() is the CLI's line for the same input.
    cli = subprocess.run([BIN, "check", scene_path("tiny_dig.yaml"), "--set", "bed.radius=-1"],
                         capture_output=True, text=True)
    assert cli.returncode == 2
    assert str(e) in cli.stderr


def test_missing_file_is_input_error():
    with pytest.raises(scoopsim.InputError) as info:
        scoopsim.load_scene(scene_path("no_such_scene.yaml"))
    assert "no_such_scene.yaml" in str(info.value)


def test_an_error_found_by_preflight_names_the_override_as_the_cli():
    # A bed of 300 spheres is too shallow for the path (sim::Preflight): the error is about
    # dig.bite_depth, and an override of it is named as the CLI names it.
    sets = ["bed.count=300", "dig.bite_depth=0.01"]
    with pytest.raises(scoopsim.InputError) as info:
        scoopsim.load_scene(scene_path("tiny_dig.yaml"), overrides=sets)
    assert info.value.key == "dig.bite_depth"
    cli = subprocess.run([BIN, "check", scene_path("tiny_dig.yaml"), "--set", sets[0], "--set",
                          sets[1]], capture_output=True, text=True)
    assert cli.returncode == 2
    assert str(info.value) in cli.stderr
    assert "--set dig.bite_depth=0.01" in str(info.value)
