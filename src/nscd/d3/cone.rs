//! The 3D Signorini–Coulomb local law (placeholder: being written).
