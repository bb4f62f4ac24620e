"""``ideas-hpc export``: a store's swarm as SPICE kernels (SPK, CK, frame and PCK kernels) and a
CSV of images. It reads stores and re-flies them through the campaign layer; nothing below
imports it."""
