//! Wire protocol between the field box and the host (not yet implemented).
