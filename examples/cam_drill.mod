MODULE CAM_DRILL
    ! A small CAM-style drilling module for examples/cell_irb6700.yaml: the panel holes in the
    ! work object wobjPanel (the cell base frame), approach by Offs, a home joint target.
    PERS tooldata tDrill:=[TRUE,[[0,0,250],[1,0,0,0]],[25,[0,0,0],[1,0,0,0],0,0,0]];
    PERS wobjdata wobjPanel:=[FALSE,TRUE,"",[[2000,300,1200],[0.5,0.5,-0.5,-0.5]],[[0,0,0],[1,0,0,0]]];
    CONST jointtarget jHome:=[[0,0,0,0,30,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pHole1:=[[100,200,-8.5],[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pHole2:=[[150.5,200,-8.5],[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
    CONST robtarget pHole3:=[[201.25,250,-8.5],[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
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
        MoveL [[250,300,-8.5],[0,0.70710678,-0.70710678,0],[0,0,-1,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]], v5, fine, tDrill\WObj:=wobjPanel;
        pProbe := CRobT(\Tool:=tDrill\WObj:=wobjPanel);
        SetDO doSpindle, 0;
        MoveAbsJ jHome\NoEOffs, v500, fine, tDrill;
    ENDPROC

    PROC Drill(robtarget p)
        MoveL p, v5, fine, tDrill\WObj:=wobjPanel;
        WaitTime 0.5;
    ENDPROC
ENDMODULE
