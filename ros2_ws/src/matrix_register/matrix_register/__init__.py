"""Registration of each drone's image to its reference view (local features, RANSAC homography).

Publishes homographies."""
