"""A ROS2 bag folder that rosbags cannot open, said as such before it is opened
(:func:`ros2_folder_check`): a folder without ``metadata.yaml``, or whose metadata
declares a storage or a message serialization rosbags does not read. The reader
(:mod:`floorscan.ingest.rosbag`) calls it first; anything else rosbags cannot read is
its "truncated or corrupt" error.
"""

from __future__ import annotations

from pathlib import Path

from floorscan.core.io import InputError

#: What rosbags reads of a ROS2 bag: its storage plugins and message serialization.
ROS2_STORAGES = ("sqlite3", "mcap")
ROS2_SERIALIZATION = "cdr"


def ros2_folder_check(path: Path) -> None:
    """A ROS2 bag folder that rosbags cannot open, said as such before it is opened.

    Parameters
    ----------
    path : Path
        A bag's path as :func:`floorscan.ingest.detect.bag_path` gives it (a ROS1 file
        is left alone).

    Raises
    ------
    InputError
        A folder without ``metadata.yaml`` (naming the storage files it holds and the
        command that writes one), or whose metadata declares a storage other than
        :data:`ROS2_STORAGES` or a serialization other than ``cdr`` (naming the topics).
    """
    if not path.is_dir():
        return
    meta = path / "metadata.yaml"
    storage = sorted(p.name for p in path.iterdir() if p.suffix.lower() in (".db3", ".mcap"))
    if not meta.is_file():
        held = f"it holds {', '.join(storage[:5])}" + (" ..." if len(storage) > 5 else "") if storage else "no .db3 or .mcap file"
        raise InputError(f"{path}: a ROS2 bag folder without its metadata.yaml ({held}); expected the folder as "
                         f"'ros2 bag record' writes it: recreate the metadata with 'ros2 bag reindex {path}'")
    import yaml

    try:
        info = (yaml.safe_load(meta.read_text()) or {}).get("rosbag2_bagfile_information") or {}
    except (OSError, yaml.YAMLError, AttributeError) as e:
        raise InputError(f"{meta}: cannot read the bag's metadata ({type(e).__name__}: {e})") from None
    store = info.get("storage_identifier")
    if store is not None and store not in ROS2_STORAGES:
        raise InputError(f"{meta}: storage_identifier {store!r}; expected one of {', '.join(ROS2_STORAGES)} "
                         "(convert the bag with 'ros2 bag convert')")
    other = sorted({(t.get("topic_metadata") or {}).get("name", "?") for t in info.get("topics_with_message_count") or []
                    if (t.get("topic_metadata") or {}).get("serialization_format", ROS2_SERIALIZATION) != ROS2_SERIALIZATION})
    if other:
        raise InputError(f"{meta}: topics {', '.join(other)} are not serialized as {ROS2_SERIALIZATION!r}; expected "
                         f"{ROS2_SERIALIZATION!r}, the serialization of ROS2's default middleware (convert the bag with "
                         "'ros2 bag convert')")
