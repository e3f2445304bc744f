"""The asset allowlist on its own: what a Foxglove client may fetch, and what it may not.

The arms here are stand-ins holding a name and a URDF whose meshes are files made in
the test's folder, so that files can be swapped for links, FIFOs and folders.
"""

from __future__ import annotations

import os
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from armfleet.foxglove import AssetLibrary, urdf_uri


def arm(name: str, *meshes: Path) -> Any:
    """A stand-in arm whose URDF references ``meshes`` by absolute path."""
    links = "".join(
        f'<link name="l{i}"><visual><geometry><mesh filename="{mesh}"/></geometry></visual></link>'
        for i, mesh in enumerate(meshes)
    )
    return SimpleNamespace(name=name, description=SimpleNamespace(urdf=f"<robot>{links}</robot>"))


@pytest.fixture
def package(tmp_path: Path) -> Path:
    """``ned_description/meshes/`` with two meshes, and a secret beside it."""
    meshes = tmp_path / "ned_description" / "meshes"
    meshes.mkdir(parents=True)
    (meshes / "base.stl").write_bytes(b"solid base")
    (meshes / "hand.stl").write_bytes(b"solid hand")
    (tmp_path / "secret.txt").write_bytes(b"secret")
    return meshes


def test_the_urdf_names_its_meshes_as_package_uris_and_both_are_served(package: Path) -> None:
    assets = AssetLibrary()
    urdf = assets.add_arm(arm("ned", package / "base.stl", package / "hand.stl"))
    assert 'filename="package://ned_description/meshes/base.stl"' in urdf
    assert str(package) not in urdf
    assert assets.fetch(urdf_uri("ned")) == urdf.encode()
    assert assets.fetch("package://ned_description/meshes/hand.stl") == b"solid hand"
    assert assets.uris == [
        "package://armfleet/robots/ned.urdf",
        "package://ned_description/meshes/base.stl",
        "package://ned_description/meshes/hand.stl",
    ]


@pytest.mark.parametrize(
    "uri",
    [
        "package://../../etc/passwd",
        "package://ned_description/../secret.txt",
        "package://ned_description/meshes/../../secret.txt",
        "package://ned_description/meshes/base.stl/../../../secret.txt",
        "package://ned_description/meshes/%2e%2e/%2e%2e/secret.txt",
        "package://ned_description/meshes//base.stl",
        "package://ned_description/meshes/base.stl/",
        "package://NED_DESCRIPTION/meshes/base.stl",
        "package://ned_description/meshes/BASE.STL",
        "package://ned_description/meshes/other.stl",
        "package://other_description/meshes/base.stl",
        "package://armfleet/robots/../../secret.txt",
        "package://armfleet/robots/bob.urdf",
        "file:///etc/passwd",
        "/etc/passwd",
        "etc/passwd",
        "",
    ],
)
def test_nothing_outside_the_allowlist_is_served(package: Path, uri: str) -> None:
    assets = AssetLibrary()
    assets.add_arm(arm("ned", package / "base.stl"))
    assert assets.fetch(uri) is None
    mesh = str(package / "base.stl")
    assert assets.fetch(mesh) is None and assets.fetch(f"file://{mesh}") is None


def test_a_mesh_swapped_for_a_link_out_is_no_longer_served(package: Path) -> None:
    assets = AssetLibrary()
    assets.add_arm(arm("ned", package / "base.stl"))
    uri = "package://ned_description/meshes/base.stl"
    assert assets.fetch(uri) == b"solid base"
    (package / "base.stl").unlink()
    (package / "base.stl").symlink_to(package.parent.parent / "secret.txt")
    assert assets.fetch(uri) is None


def test_a_folder_swapped_for_a_link_out_is_no_longer_served(package: Path, tmp_path: Path) -> None:
    assets = AssetLibrary()
    assets.add_arm(arm("ned", package / "base.stl"))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (elsewhere / "base.stl").write_bytes(b"not the mesh")
    package.rename(tmp_path / "moved")
    package.symlink_to(elsewhere)
    assert assets.fetch("package://ned_description/meshes/base.stl") is None


def test_a_fifo_or_a_folder_in_a_mesh_s_place_is_refused_without_blocking(package: Path) -> None:
    assets = AssetLibrary()
    assets.add_arm(arm("ned", package / "base.stl", package / "hand.stl"))
    (package / "base.stl").unlink()
    os.mkfifo(package / "base.stl")  # opening it for reading would wait for a writer
    (package / "hand.stl").unlink()
    (package / "hand.stl").mkdir()
    assert assets.fetch("package://ned_description/meshes/base.stl") is None
    assert assets.fetch("package://ned_description/meshes/hand.stl") is None


def test_a_mesh_referenced_through_a_link_is_served_as_its_real_file(
    package: Path, tmp_path: Path
) -> None:
    (tmp_path / "link.stl").symlink_to(package / "hand.stl")
    assets = AssetLibrary()
    urdf = assets.add_arm(arm("ned", tmp_path / "link.stl"))
    assert "package://ned_description/meshes/hand.stl" in urdf
    assert assets.fetch("package://ned_description/meshes/hand.stl") == b"solid hand"


def test_meshes_outside_a_description_package_get_a_package_of_their_own(tmp_path: Path) -> None:
    for folder in ("a", "b"):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "mesh.stl").write_bytes(folder.encode())
    assets = AssetLibrary()
    urdf = assets.add_arm(arm("ned", tmp_path / "a" / "mesh.stl", tmp_path / "b" / "mesh.stl"))
    uris = [u for u in assets.uris if "mesh.stl" in u]
    assert len(uris) == 2 and all(u.startswith("package://armfleet_files_") for u in uris)
    assert sorted(assets.fetch(u) or b"" for u in uris) == [b"a", b"b"]
    assert all(u in urdf for u in uris)


def test_a_removed_arm_s_urdf_goes_and_a_shared_mesh_stays_while_used(package: Path) -> None:
    assets = AssetLibrary()
    assets.add_arm(arm("ned", package / "base.stl", package / "hand.stl"))
    assets.add_arm(arm("tom", package / "base.stl"))
    assets.remove_arm("ned")
    assert assets.fetch(urdf_uri("ned")) is None
    assert assets.fetch("package://ned_description/meshes/hand.stl") is None
    assert assets.fetch("package://ned_description/meshes/base.stl") == b"solid base"
