//! GNSS/INS.
