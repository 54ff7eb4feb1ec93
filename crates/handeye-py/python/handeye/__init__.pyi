"""Type stubs of handeye. Frames: base_from_gripper (OpenCV gripper2base), camera_from_target
(target2cam); X = gripper_from_camera (cam2gripper) for eye-in-hand, base_from_camera for
eye-to-hand."""
import os
from typing import Optional, Any, Mapping, Sequence, Union

import numpy as np
import numpy.typing as npt

METHODS: dict[int, str]
ROBOT_WORLD_METHODS: dict[int, str]

def calibrate_hand_eye(
    R_gripper2base: Sequence[npt.ArrayLike],
    t_gripper2base: Sequence[npt.ArrayLike],
    R_target2cam: Sequence[npt.ArrayLike],
    t_target2cam: Sequence[npt.ArrayLike],
    method: Union[int, str] = 0,
    setup: Optional[str] = None,
) -> tuple[np.ndarray, np.ndarray]: ...
def calibrate_robot_world_hand_eye(
    R_world2cam: Sequence[npt.ArrayLike],
    t_world2cam: Sequence[npt.ArrayLike],
    R_base2gripper: Sequence[npt.ArrayLike],
    t_base2gripper: Sequence[npt.ArrayLike],
    method: Union[int, str] = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]: ...
def calibrate(
    base_from_gripper: Optional[Union[npt.ArrayLike, str, "os.PathLike[str]"]] = None,
    camera_from_target: Optional[npt.ArrayLike] = None,
    method: Optional[str] = None,
    setup: str = "eye-in-hand",
    pairs: Optional[str] = None,
    reject_outliers: bool = False,
    fix: Optional[str] = None,
    bootstrap: int = 40,
    robot_world: bool = False,
    tsai_opencv_filter: bool = False,
    point: Optional[npt.ArrayLike] = None,
    joints: Optional[Sequence[Sequence[float]]] = None,
    prior: Optional[Union[str, Sequence[str], Mapping[str, Union[float, tuple[float, float]]]]] = None,
    robot_model: Optional[Union[str, "os.PathLike[str]"]] = None,
    *,
    path: Optional[Union[str, "os.PathLike[str]"]] = None,
    intrinsics: Optional[Union[str, "os.PathLike[str]"]] = None,
    refine_intrinsics: bool = False,
    base_frame: Optional[str] = None,
    gripper_frame: Optional[str] = None,
    camera_frame: Optional[str] = None,
    target_topic: Optional[str] = None,
    tag_size: Optional[float] = None,
    tag_id: Optional[int] = None,
    camera_info_topic: Optional[str] = None,
    time_offset: Optional[Union[float, str]] = None,
    max_gap: float = 0.1,
    goal: Optional[tuple[float, float]] = None,
) -> dict[str, Any]: ...

def advise(
    base_from_gripper: npt.ArrayLike,
    camera_from_target: npt.ArrayLike,
    setup: str = "eye-in-hand",
    count: int = 3,
    prior: Optional[Union[str, Sequence[str], Mapping[str, Union[float, tuple[float, float]]]]] = None,
    goal: Optional[tuple[float, float]] = None,
) -> dict[str, Any]: ...

def verify(
    saved: Union[str, "os.PathLike[str]"],
    base_from_gripper: npt.ArrayLike,
    camera_from_target: npt.ArrayLike,
    *,
    setup: Optional[str] = None,
    method: Optional[str] = None,
    pairs: Optional[str] = None,
    reject_outliers: bool = False,
    bootstrap: int = 40,
    joints: Optional[Sequence[Sequence[float]]] = None,
    prior: Optional[Union[str, Sequence[str], Mapping[str, Union[float, tuple[float, float]]]]] = None,
    fix: Optional[str] = None,
    tolerance: Optional[tuple[float, float]] = None,
) -> dict[str, Any]: ...

def calibrate_on_pixels(
    path: Union[str, "os.PathLike[str]"],
    intrinsics: Optional[Union[str, "os.PathLike[str]"]] = None,
    *,
    setup: str = "eye-in-hand",
    robot_world: bool = False,
    fix: Optional[str] = None,
    point: Optional[Sequence[float]] = None,
    refine_intrinsics: bool = False,
    base_frame: Optional[str] = None,
    gripper_frame: Optional[str] = None,
    camera_frame: Optional[str] = None,
    target_topic: Optional[str] = None,
    tag_size: Optional[float] = None,
    tag_id: Optional[int] = None,
    camera_info_topic: Optional[str] = None,
    time_offset: Optional[Union[float, str]] = None,
    max_gap: float = 0.1,
) -> dict[str, Any]: ...

def verify_on_pixels(
    saved: Union[str, "os.PathLike[str]"],
    path: Union[str, "os.PathLike[str]"],
    intrinsics: Union[str, "os.PathLike[str]"],
    *,
    setup: Optional[str] = None,
    fix: Optional[str] = None,
    tolerance: Optional[tuple[float, float]] = None,
) -> dict[str, Any]: ...

def read_recording(
    path: Optional[Union[str, "os.PathLike[str]"]] = None,
    *,
    format: str = "auto",
    robot: Optional[Union[str, "os.PathLike[str]"]] = None,
    camera: Optional[Union[str, "os.PathLike[str]"]] = None,
    base_frame: Optional[str] = None,
    gripper_frame: Optional[str] = None,
    camera_frame: Optional[str] = None,
    target_frame: Optional[str] = None,
    target_topic: Optional[str] = None,
    setup: str = "eye-in-hand",
    time_offset: Optional[Union[float, str]] = None,
    max_gap: float = 0.1,
    rotation: Optional[Union[str, Sequence[str], Mapping[str, str]]] = None,
) -> dict[str, Any]: ...

class OnlineCalibrator:
    def __init__(
        self,
        *,
        prior: Optional[Union[str, Sequence[str], Mapping[str, Union[float, tuple[float, float]]]]] = None,
        robot_model: Optional[Union[str, "os.PathLike[str]"]] = None,
        **params: Any,
    ) -> None: ...
    def push(self, base_from_gripper: npt.ArrayLike, camera_from_target: npt.ArrayLike) -> list[dict[str, Any]]: ...
    def push_detections(
        self,
        base_from_gripper: npt.ArrayLike,
        detections: Mapping[str, Any],
        camera_from_target: Optional[npt.ArrayLike] = None,
    ) -> list[dict[str, Any]]: ...
    def push_record(self, line: str) -> list[dict[str, Any]]: ...
    def finish(self) -> Optional[dict[str, Any]]: ...
    def last_report(self) -> Optional[dict[str, Any]]: ...
    def pending(self) -> Optional[str]: ...
    @property
    def poses(self) -> int: ...
    @property
    def calibrations(self) -> int: ...
    def state(self) -> str: ...
    @classmethod
    def from_state(cls, state: str) -> "OnlineCalibrator": ...
