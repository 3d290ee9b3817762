MODULE CAM_DRILL
    ! accugrid 0.1.0 rewrite
    ! program cam_drill.mod sha256 21b9d3dd78905f3f7aa5c88a8f05057f503e1189cbd9f8d78f98362b3164a71a
    ! cell cell_irb6700.yaml sha256 a9446f38a6cfb11d74737f0a3b472333dd0344b840e04abc0177f0fb2a39a2f3
    ! grid grid_irb6700_200mm.csv sha256 a595bed6b2ca0d6ce01bb72e1888c2462fdd63e98a49c3ba94f7576afe7e2791
    ! grid step 200.000 x 200.000 x 200.000 mm
    ! largest correction 3.923 mm at pHole3 line 9
    ! largest u95 0.113 mm over 2 positions: the 95 percent bound of the error
    ! positions corrected 2
    ! not corrected: line 7 pHole1: used by Drill at line 15, not a move accugrid places
    ! not corrected: line 8 pHole2: operand of Offs_..._ at line 16: the offset point is not a drilling position
    ! A small CAM-style drilling module for examples/cell_irb6700.yaml: the panel holes in the
    ! work object wobjPanel (the cell base frame), approach by Offs, a home joint target.
    PERS tooldata tDrill:=[TRUE,[[0,0,250],[1,0,0,0]],[25,[0,0,0],[1,0,0,0],0,0,0]];
    PERS wobjdata wobjPanel:=[FALSE,TRUE,"",[[2000,300,1200],[0.5,0.5,-0.5,-0.5]],[[0,0,0],[1,0,0,0]]];
    CONST jointtarget jHome:=[[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pHole1:=[[100,200,-8.5],[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pHole2:=[[150.5,200,-8.5],[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pHole3:=[[200.63,253.76,-7.57],[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    VAR robtarget pProbe:=[[300,300,0],[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];

    PROC main()
        MoveAbsJ jHome\NoEOffs, v500, fine, tDrill;
        SetDO doSpindle, 1;
        Drill pHole1;
        MoveL Offs(pHole2,0,0,30), v200, z5, tDrill\WObj:=wobjPanel;
        MoveL pHole2, v5, fine, tDrill\WObj:=wobjPanel;
        WaitTime 0.5;
        MoveJ pHole3, v200, z5, tDrill\WObj:=wobjPanel;
        MoveL pHole3, v5, fine, tDrill\WObj:=wobjPanel;
        MoveL [[249.37,303.75,-7.56],[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]], v5, fine, tDrill\WObj:=wobjPanel;
        pProbe := CRobT(\Tool:=tDrill\WObj:=wobjPanel);
        SetDO doSpindle, 0;
        MoveAbsJ jHome\NoEOffs, v500, fine, tDrill;
    ENDPROC

    PROC Drill(robtarget p)
        MoveL p, v5, fine, tDrill\WObj:=wobjPanel;
        WaitTime 0.5;
    ENDPROC
ENDMODULE
