//! Virtual hardware for triquint: drives running the real firmware core, a bus, and a plant.
