//! Contact detection between 3D solids (placeholder: being written).
