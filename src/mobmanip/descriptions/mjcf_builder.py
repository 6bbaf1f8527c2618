"""How an MJCF description builds Pinocchio's model and geometry (:class:`MjcfBuilder`)."""

from __future__ import annotations

import tempfile
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any
from xml.etree import ElementTree

import numpy as np

from ..errors import MjcfError
from ..support.native_stderr import call_with_large_stack, captured_native_stderr
from .description import (
    MeshFilter,
    ModelBuilder,
    geometry_type,
)

if TYPE_CHECKING:
    import pinocchio as pin

#: Actuator elements: all set the attributes of MuJoCo's ``general`` actuator.


class MjcfBuilder(ModelBuilder):
    """An MJCF's text for Pinocchio (``buildModelFromMJCF``, ``buildGeomFromMJCF``), written to a
    temporary file when a model is built (Pinocchio reads MJCF from files only).

    Args:
        text: the MJCF as mobmanip rewrote it: includes expanded, the root's free joint dropped, a
            body with several joints split, unnamed elements named, asset folders absolute.
        notes: what the reader skipped.
        platform_armature: the armature of the file's own planar base joints (kg, kg, kg m^2),
            which mobmanip's platform joint replaces: the yaw's on a planar root joint's yaw rate,
            the slides' (equal, see :func:`~mobmanip.descriptions.mjcf._platform_armature`) as a
            point mass on the yaw axis (see :meth:`build_model`); Pinocchio reads every other
            joint's ``armature`` itself.
    """

    language = "MJCF"

    def __init__(
        self, text: str, notes: tuple[str, ...] = (), platform_armature: tuple[float, float, float] | None = None
    ) -> None:
        self.text = text
        self.notes = notes
        self.platform_armature = platform_armature

    def error(self, source: str, reason: str) -> MjcfError:
        """A :class:`~mobmanip.errors.MjcfError` naming ``source``."""
        return MjcfError(source, reason)

    def _call(self, source: str, what: str, function: Any, *arguments: Any, text: str | None = None) -> Any:
        with tempfile.TemporaryDirectory(prefix="mobmanip-mjcf-") as folder:
            file = Path(folder) / "model.xml"
            file.write_text(self.text if text is None else text, encoding="utf-8")
            failure: Exception | None = None
            with captured_native_stderr() as native, warnings.catch_warnings():
                warnings.simplefilter("ignore", DeprecationWarning)
                try:
                    result = call_with_large_stack(function, *[str(file) if a is _FILE else a for a in arguments])
                except Exception as exc:  # Pinocchio raises ValueError/RuntimeError on what it cannot build
                    result, failure = None, exc
        if result is None:
            reason = native.first_error() or " ".join(str(failure).split()).replace(str(file), Path(source).name)
            raise MjcfError(source, f"Pinocchio cannot {what}: {reason}")
        return result

    def build_model(self, source: str, root_joint: pin.JointModel | None = None) -> pin.Model:
        """Pinocchio's model under ``root_joint`` (see :meth:`ModelBuilder.build_model`)."""
        import pinocchio as pin

        if root_joint is None:
            return self._call(source, "build a model", pin.buildModelFromMJCF, _FILE)
        model = self._call(source, "build a model", pin.buildModelFromMJCFAndRootJoint, _FILE, root_joint)
        root = model.joints[1] if model.njoints > 1 else None
        if self.platform_armature is not None and root is not None and root.shortname() == "JointModelPlanar":
            # The slides' armature is kinetic energy a/2 (x'^2 + y'^2) along the world's axes, which
            # is a/2 |v|^2 in the platform's turning frame: a point mass a on the yaw axis, whose
            # gyroscopic term (omega x a v) is in the bias. On the joint's diagonal (model.armature)
            # the mass matrix would be the same but that term would be missing from the bias.
            along, _, yaw = self.platform_armature
            armature = np.array(model.armature, dtype=float)
            armature[root.idx_v : root.idx_v + 3] = (0.0, 0.0, yaw)
            model.armature = armature
            model.inertias[1] = model.inertias[1] + pin.Inertia(along, np.zeros(3), np.zeros((3, 3)))
        return model

    def load_geometry(self, source: str, model: pin.Model, kind: str, text: str, dirs: list[str]) -> pin.GeometryModel:
        """The geoms of ``text`` on ``model`` (see :meth:`ModelBuilder.load_geometry`); its mesh
        files are absolute (``dirs`` plays no part)."""
        import pinocchio as pin

        what = f"load the {kind} geometry"
        return self._call(source, what, pin.buildGeomFromMJCF, model, _FILE, geometry_type(kind), text=text)

    def with_meshes(self, kind: str, meshes: MeshFilter) -> str:
        """The text with each mesh file replaced by the file ``meshes`` gives, or its geoms left
        out (of either kind: an MJCF geom is both)."""
        root = ElementTree.fromstring(self.text)
        meshdir = Path((root.find("compiler") or ElementTree.Element("compiler")).get("meshdir", ""))
        dropped = set()
        for asset in root.iter("asset"):
            for mesh in list(asset.findall("mesh")):
                file = mesh.get("file", "")
                name = mesh.get("name") or Path(file).stem
                replacement = meshes("", str(meshdir / file))
                if replacement is None:
                    asset.remove(mesh)
                    dropped.add(name)
                else:
                    mesh.set("name", name)
                    mesh.set("file", str(Path(replacement).resolve()))
        for parent in root.iter():
            for geom in list(parent.findall("geom")):
                if geom.get("mesh") in dropped:
                    parent.remove(geom)
        for texture in root.iter("texture"):
            texture.attrib.pop("file", None)
        return ElementTree.tostring(root, encoding="unicode")


_FILE = object()  # stands for the temporary file's path in a builder call
