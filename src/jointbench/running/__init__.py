"""Running a study: the simulate, poses and estimate jobs, scoring estimates against the truth,
collecting a study's estimates files and summarising them."""
