//! Report pieces shared by `fit` and `discover`: parameter tables and overlays.
