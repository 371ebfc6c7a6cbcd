"""What-ifs on a design: :mod:`.tolerance` (bands under manufacturing tolerances),
:mod:`.sensitivity` (which parameter moves the stiffness) and :mod:`.target` (designs that meet
target stiffnesses)."""
