//! Surface metrics: profile (ISO 4287 / 21920-2) and areal (ISO 25178-2) parameters,
//! levelling, polynomial form removal and Gaussian filters.
