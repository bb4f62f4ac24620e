"""Campaigns: TOML files of kind flyby, design-nadir, design-fov or monte-carlo
(SPEC section 8), validated once (:mod:`.schema`), run (:mod:`.run`) into zarr
stores (:mod:`.datasets`), and reported (:mod:`.report`)."""
