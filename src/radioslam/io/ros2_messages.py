"""The ROS 2 message definitions a radioslam bag uses (issue #17), as ``ros2msg`` text with every dependency
(the form MCAP's ``ros2`` profile stores in a schema, and Foxglove and RViz 2 decode with): the interfaces of
ROS 2 Humble's common_interfaces, written out here so that no ROS install is needed."""

from __future__ import annotations

SEPARATOR = "=" * 80

_DEFINITIONS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec",
    "builtin_interfaces/Duration": "int32 sec\nuint32 nanosec",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "std_msgs/ColorRGBA": "float32 r\nfloat32 g\nfloat32 b\nfloat32 a",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    "geometry_msgs/Pose": "Point position\nQuaternion orientation",
    "geometry_msgs/PoseStamped": "std_msgs/Header header\nPose pose",
    "geometry_msgs/Transform": "Vector3 translation\nQuaternion rotation",
    "geometry_msgs/TransformStamped": "std_msgs/Header header\nstring child_frame_id\nTransform transform",
    "sensor_msgs/PointField": ("uint8 INT8 = 1\nuint8 UINT8 = 2\nuint8 INT16 = 3\nuint8 UINT16 = 4\nuint8 INT32 = 5\n"
                               "uint8 UINT32 = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\n"
                               "string name\nuint32 offset\nuint8 datatype\nuint32 count"),
    "sensor_msgs/PointCloud2": ("std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\n"
                                "bool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense"),
    "nav_msgs/Path": "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses",
    "nav_msgs/MapMetaData": ("builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\n"
                             "geometry_msgs/Pose origin"),
    "nav_msgs/OccupancyGrid": "std_msgs/Header header\nMapMetaData info\nint8[] data",
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms",
    "visualization_msgs/Marker": (
        "int32 ARROW=0\nint32 CUBE=1\nint32 SPHERE=2\nint32 CYLINDER=3\nint32 LINE_STRIP=4\nint32 LINE_LIST=5\n"
        "int32 CUBE_LIST=6\nint32 SPHERE_LIST=7\nint32 POINTS=8\nint32 TEXT_VIEW_FACING=9\nint32 MESH_RESOURCE=10\n"
        "int32 TRIANGLE_LIST=11\nint32 ADD=0\nint32 MODIFY=0\nint32 DELETE=2\nint32 DELETEALL=3\n"
        "std_msgs/Header header\nstring ns\nint32 id\nint32 type\nint32 action\ngeometry_msgs/Pose pose\n"
        "geometry_msgs/Vector3 scale\nstd_msgs/ColorRGBA color\nbuiltin_interfaces/Duration lifetime\n"
        "bool frame_locked\ngeometry_msgs/Point[] points\nstd_msgs/ColorRGBA[] colors\nstring text\n"
        "string mesh_resource\nbool mesh_use_embedded_materials"),
    "visualization_msgs/MarkerArray": "Marker[] markers",
}

PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16", "int32", "uint32",
              "int64", "uint64", "string", "wstring"}


def _field_types(name: str) -> list[str]:
    """The message types ``name``'s fields use, fully named (a bare type is in ``name``'s package)."""
    package = name.split("/")[0]
    types = [line.split()[0].split("[")[0] for line in _DEFINITIONS[name].splitlines()]
    return [t if "/" in t else f"{package}/{t}" for t in types if t not in PRIMITIVES]


def _closure(name: str) -> list[str]:
    """Every type ``name`` depends on, depth first, each once."""
    seen: list[str] = []

    def visit(n: str) -> None:
        for dep in _field_types(n):
            if dep not in seen:
                seen.append(dep)
                visit(dep)

    visit(name)
    return seen


def message_definition(name: str) -> str:
    """The ``ros2msg`` schema text of ``name`` (e.g. ``sensor_msgs/msg/PointCloud2`` or
    ``sensor_msgs/PointCloud2``): its own definition, then each dependency after a separator line."""
    short = name.replace("/msg/", "/")
    parts = [_DEFINITIONS[short]]
    for dep in _closure(short):
        parts.append(f"{SEPARATOR}\nMSG: {dep}\n{_DEFINITIONS[dep]}")
    return "\n".join(parts) + "\n"
