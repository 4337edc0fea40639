//! Chi-square goodness-of-fit test of a direction sampler against its pdf.
