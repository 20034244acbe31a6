//! cablab
