"""A URDF file as MuJoCo's spec of it, for ``robot_file.robot_spec``: the file read as data (ElementTree: nothing in it
runs), each collision mesh's path resolved (``package://NAME/...`` against the definition's ``package_root``,
others against the file's folder) and checked, the visual elements dropped (the scene is for stepping), and
MuJoCo's URDF compiler told to keep every link (``fusestatic`` off: the feet are links of their own, hung by fixed
joints) and every path as written."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET


def resolve_mesh(filename: str, urdf: str, package_root: str) -> str:
    """The path of a mesh a URDF names, or one line naming the mesh and the fix."""
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    if filename.startswith("package://"):
        package, _, rest = filename[len("package://"):].partition("/")
        if not package_root:
            raise ValueError(f"{urdf}: mesh {filename!r} is in ROS package {package!r}: set package_root to that "
                             "package's folder (or the folder that holds it)")
        tries = [os.path.join(package_root, rest), os.path.join(package_root, package, rest)]
    else:
        tries = [filename if os.path.isabs(filename) else os.path.join(os.path.dirname(os.path.abspath(urdf)), filename)]
    for path in tries:
        if os.path.isfile(path):
            return os.path.abspath(path)
    raise ValueError(f"{urdf}: mesh {filename!r} is missing (looked for {' and '.join(tries)}): put it there, or "
                     "fix the path" + (" or package_root" if filename.startswith("package://") else ""))


def urdf_spec(path: str, package_root: str = "", balance_inertia: bool = False):
    """MuJoCo's spec of the URDF at ``path`` (its root link a child of the world, without a joint)."""
    import mujoco  # noqa: PLC0415

    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise ValueError(f"{path}: not a readable URDF ({e}): fix the XML") from None
    if root.tag != "robot":
        raise ValueError(f"{path}: its root element is <{root.tag}>, a URDF's is <robot>: give a URDF or an MJCF file")
    for link in root.iter("link"):
        for visual in link.findall("visual"):
            link.remove(visual)
    for mesh in root.iter("mesh"):
        mesh.set("filename", resolve_mesh(mesh.get("filename", ""), path, package_root))
    for old in root.findall("mujoco"):
        root.remove(old)
    ext = ET.SubElement(root, "mujoco")
    ET.SubElement(ext, "compiler", {"fusestatic": "false", "discardvisual": "true", "strippath": "false",
                                    "balanceinertia": "true" if balance_inertia else "false"})
    try:
        return mujoco.MjSpec.from_string(ET.tostring(root, encoding="unicode"))
    except ValueError as e:  # a compile's refusals (an inertia, say) come later, robot_file.compile_robot_scene's
        raise ValueError(f"{path}: MuJoCo cannot read this URDF: {' '.join(str(e).split())}") from None
