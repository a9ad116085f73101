"""Camera geometry: projection, back-projection, the image of an ellipsoid, calibration."""

from worldtrack.geometry.camera import Camera, intrinsics_from_fov, normalise_projection

__all__ = ["Camera", "intrinsics_from_fov", "normalise_projection"]
