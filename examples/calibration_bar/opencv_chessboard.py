"""OpenCV's chessboard calibration on the views calibration_bar rendered.

Reads one JSON object on stdin:
  {"images": [paths], "pattern": [cols, rows] (inner corners),
   "corners_mm": [[x, y], ...] (row by row, `cols` per row),
   "width": w, "height": h,
   "pnp_camera": {"K": [9 values], "dist": [5 values]} (optional)}
and prints one JSON object: which images showed the board, the corners
found, calibrateCamera's result, and with pnp_camera each view's solvePnP
pose (rotation vector, translation in metres) through that camera.
"""

import json
import sys

import cv2
import numpy as np


def main():
    job = json.load(sys.stdin)
    cols, rows = job["pattern"]
    object_points = np.array(
        [[x / 1000.0, y / 1000.0, 0.0] for x, y in job["corners_mm"]], dtype=np.float32
    )
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-4)
    found_flags, image_points, object_sets, corners_out = [], [], [], []
    for path in job["images"]:
        gray = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
        found, corners = cv2.findChessboardCorners(
            gray,
            (cols, rows),
            flags=cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE,
        )
        if found:
            # The refinement window must stay inside the squares around a
            # corner, or it reaches the next corners and pulls towards
            # them: steep or distant views make squares of 15-20 px, where
            # OpenCV's usual 11 (a 23 px window) does. Half the shortest
            # side between neighbouring corners, at most 11.
            grid = corners.reshape(rows, cols, 2)
            sides = np.concatenate(
                [
                    np.linalg.norm(np.diff(grid, axis=0), axis=2).ravel(),
                    np.linalg.norm(np.diff(grid, axis=1), axis=2).ravel(),
                ]
            )
            half = int(max(3, min(11, sides.min() / 2)))
            corners = cv2.cornerSubPix(gray, corners, (half, half), (-1, -1), criteria)
            image_points.append(corners)
            object_sets.append(object_points)
            corners_out.append(corners.reshape(-1, 2).tolist())
        else:
            corners_out.append(None)
        found_flags.append(bool(found))
    result = {"found": found_flags, "corners": corners_out}
    if len(image_points) >= 3:
        rms, K, dist, _, _ = cv2.calibrateCamera(
            object_sets,
            image_points,
            (job["width"], job["height"]),
            None,
            None,
            criteria=(cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 100, 1e-12),
        )
        result.update(
            rms=float(rms),
            camera_matrix=K.reshape(-1).tolist(),
            dist=dist.reshape(-1)[:5].tolist(),
        )
    if "pnp_camera" in job:
        K = np.array(job["pnp_camera"]["K"], dtype=np.float64).reshape(3, 3)
        dist = np.array(job["pnp_camera"]["dist"], dtype=np.float64)
        poses = []
        for corners in corners_out:
            if corners is None:
                poses.append(None)
                continue
            pts = np.array(corners, dtype=np.float64).reshape(-1, 1, 2)
            ok, rvec, tvec = cv2.solvePnP(
                object_points.astype(np.float64), pts, K, dist, flags=cv2.SOLVEPNP_ITERATIVE
            )
            poses.append(
                {"rvec": rvec.reshape(-1).tolist(), "tvec": tvec.reshape(-1).tolist()}
                if ok
                else None
            )
        result["pnp"] = poses
    result["opencv"] = cv2.__version__
    json.dump(result, sys.stdout)


if __name__ == "__main__":
    main()
