//! Certification reports.
