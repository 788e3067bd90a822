"""The paper reproduced: Table 1, the errata, and the contact fitted to its measured numbers."""
