"""A source that is images: the probe scene written out for a renderer the tool cannot drive
(`export`), and the images its user renders of it read back as a source (`folder`), their calibration
checked before anything is fitted (`calibrate`)."""
